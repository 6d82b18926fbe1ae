//! Stored metamodels, and the exceedance curves sampled from them.

use super::{ApiJson, ApiQuery, Page, accept_job};
use crate::analysis::exceedance_svg;
use crate::problem::Problem;
use crate::service::error::{ApiError, ProblemDetails};
use crate::service::exceedance::{ExceedanceAnswer, ExceedanceJob, ExceedanceRequest};
use crate::service::routes::operations::{Operation, OperationKind};
use crate::service::{AppState, MAX_VALIDATION_SAMPLES, ValidationJob, ValidationRequest};
use crate::surrogate::{Metamodel, Silent};
use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response as HttpResponse};
use serde::Serialize;
use std::sync::Arc;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(list_metamodels))
        .routes(routes!(get_metamodel, delete_metamodel))
        .routes(routes!(exceedance_curve))
        .routes(routes!(start_validation))
}

/// A stored metamodel in a list.
#[derive(Debug, Serialize, ToSchema)]
pub struct MetamodelSummary {
    pub id: String,
    /// The calibration that produced it.
    pub operation_id: Option<String>,
    /// The study's name (a preset or `custom`).
    pub preset: String,
    pub created_at_ms: i64,
}

#[derive(Debug, Serialize, ToSchema)]
pub struct MetamodelList {
    pub metamodels: Vec<MetamodelSummary>,
    pub limit: i64,
    pub offset: i64,
}

/// Stored metamodels, newest first.
#[utoipa::path(get, path = "/v1/metamodels", tag = "metamodels", params(Page),
    responses(
        (status = 200, description = "A page of metamodels", body = MetamodelList),
        (status = 422, description = "limit or offset out of range", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn list_metamodels(
    State(state): State<AppState>,
    ApiQuery(page): ApiQuery<Page>,
) -> Result<Json<MetamodelList>, ApiError> {
    page.check()?;
    let rows = state.store.metamodels(page.limit, page.offset).await?;
    let metamodels = rows
        .into_iter()
        .map(|r| MetamodelSummary { id: r.id, operation_id: r.job_id, preset: r.preset, created_at_ms: r.created_at })
        .collect();
    Ok(Json(MetamodelList { metamodels, limit: page.limit, offset: page.offset }))
}

/// The full metamodel: coefficients and diagnostics, enough to reproduce predictions elsewhere.
#[utoipa::path(get, path = "/v1/metamodels/{id}", tag = "metamodels",
    params(("id" = String, Path, description = "Metamodel id")),
    responses(
        (status = 200, description = "The metamodel document (format `windmeta-pc-narx`)", body = Metamodel),
        (status = 404, description = "No such metamodel", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn get_metamodel(State(state): State<AppState>, Path(id): Path<String>) -> Result<HttpResponse, ApiError> {
    let body = state.store.metamodel_body(&id).await?.ok_or_else(|| ApiError::not_found("metamodel", &id))?;
    Ok(([(header::CONTENT_TYPE, "application/json")], body).into_response())
}

/// Deletes a metamodel (operations that refer to it keep their record).
#[utoipa::path(delete, path = "/v1/metamodels/{id}", tag = "metamodels",
    params(("id" = String, Path, description = "Metamodel id")),
    responses(
        (status = 204, description = "Deleted"),
        (status = 404, description = "No such metamodel", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn delete_metamodel(State(state): State<AppState>, Path(id): Path<String>) -> Result<StatusCode, ApiError> {
    if !state.store.delete_metamodel(&id).await? {
        return Err(ApiError::not_found("metamodel", &id));
    }
    state.loaded.lock().expect("cache lock").remove(&id);
    Ok(StatusCode::NO_CONTENT)
}

/// A stored metamodel and its rebuilt study, cached by id. A cached one is still looked up in the
/// store (one indexed read), so a delete through another replica is seen at once.
pub async fn load(state: &AppState, id: &str) -> Result<crate::service::Loaded, ApiError> {
    let (cached, generation) = {
        let mut loaded = state.loaded.lock().expect("cache lock");
        (loaded.get(id), loaded.generation())
    };
    if let Some(found) = cached {
        if state.store.metamodel_exists(id).await? {
            return Ok(found);
        }
        state.loaded.lock().expect("cache lock").remove(id);
        return Err(ApiError::not_found("metamodel", id));
    }
    let body = state.store.metamodel_body(id).await?.ok_or_else(|| ApiError::not_found("metamodel", id))?;
    let loaded = tokio::task::spawn_blocking(move || -> crate::error::Result<(Metamodel, Problem)> {
        let metamodel = Metamodel::from_json(&body)?;
        let problem = metamodel.problem()?;
        Ok((metamodel, problem))
    })
    .await
    .map_err(ApiError::internal)??;
    let loaded = Arc::new(loaded);
    state.loaded.lock().expect("cache lock").insert(id, loaded.clone(), generation);
    Ok(loaded)
}

/// Whether the client asked for the answer as an operation (RFC 7240 `Prefer: respond-async`).
fn prefers_async(headers: &HeaderMap) -> bool {
    headers
        .get_all("prefer")
        .iter()
        .filter_map(|v| v.to_str().ok())
        .any(|v| v.split(',').any(|p| p.trim().eq_ignore_ascii_case("respond-async")))
}

/// The peak-response exceedance curve with its band, sampled from the metamodel: JSON, CSV or SVG
/// by `Accept`. Requests above the server's synchronous limit (or with `Prefer: respond-async`)
/// run as an operation whose `result` is the JSON curve.
#[utoipa::path(post, path = "/v1/metamodels/{id}/exceedance", tag = "metamodels",
    request_body = ExceedanceRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Prefer" = Option<String>, Header, description = "`respond-async` to run the request as an operation"),
        ("Idempotency-Key" = Option<String>, Header, description = "Makes a retry of an asynchronous request return the same operation"),
    ),
    responses(
        (status = 200, description = "The curve", content(
            (ExceedanceAnswer = "application/json"),
            (String = "text/csv", example = "threshold_m,probability,lower,upper\n0.31,1,0.996,1\n"),
            (String = "image/svg+xml"),
        )),
        (status = 202, description = "Queued as an operation; follow `Location`", body = Operation,
            headers(("Location" = String, description = "The operation"), ("Retry-After" = u64, description = "Seconds before polling"))),
        (status = 404, description = "No such metamodel", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 422, description = "A field is invalid (named in `errors`), or a sample diverged", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 503, description = "The queue is full (asynchronous requests)", body = ProblemDetails, content_type = "application/problem+json",
            headers(("Retry-After" = u64, description = "Seconds before trying again"))),
    ))]
async fn exceedance_curve(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<ExceedanceRequest>,
) -> Result<HttpResponse, ApiError> {
    request.check(&state.config)?;
    let loaded = load(&state, &id).await?;
    if request.samples > state.config.max_sync_samples || prefers_async(&headers) {
        let job = ExceedanceJob { metamodel_id: id, request };
        let text = serde_json::to_string(&job).expect("a job serialises");
        return accept_job(&state, &headers, "exceedance", OperationKind::Exceedance, text).await;
    }
    let accept = headers.get(header::ACCEPT).and_then(|v| v.to_str().ok()).unwrap_or("application/json").to_string();
    let answer = tokio::task::spawn_blocking(move || {
        let (metamodel, problem) = loaded.as_ref();
        request.answer(metamodel, problem, &id, &Silent)
    })
    .await
    .map_err(ApiError::internal)??;
    let curve = &answer.curve;
    if accept.contains("text/csv") {
        let mut text = String::from("threshold_m,probability,lower,upper\n");
        for i in 0..curve.thresholds.len() {
            text +=
                &format!("{},{},{},{}\n", curve.thresholds[i], curve.probabilities[i], curve.lower[i], curve.upper[i]);
        }
        return Ok(([(header::CONTENT_TYPE, "text/csv")], text).into_response());
    }
    if accept.contains("image/svg+xml") {
        let svg = exceedance_svg(&[("PC-NARX", curve)], &format!("peak {:?} x (m)", answer.response));
        return Ok(([(header::CONTENT_TYPE, "image/svg+xml")], svg).into_response());
    }
    Ok(Json(answer).into_response())
}

/// Validates the metamodel against the reference model on fresh samples, as an operation whose
/// `result` is the comparison (correlation, errors, both curves).
#[utoipa::path(post, path = "/v1/metamodels/{id}/validations", tag = "metamodels",
    request_body = ValidationRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Idempotency-Key" = Option<String>, Header, description = "Makes a retry return the same operation"),
    ),
    responses(
        (status = 202, description = "Queued; follow `Location`", body = Operation,
            headers(("Location" = String, description = "The operation"), ("Retry-After" = u64, description = "Seconds before polling"))),
        (status = 404, description = "No such metamodel", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 422, description = "A field is invalid (named in `errors`), or the Idempotency-Key was used with another request", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 503, description = "The queue is full", body = ProblemDetails, content_type = "application/problem+json",
            headers(("Retry-After" = u64, description = "Seconds before trying again"))),
    ))]
async fn start_validation(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<ValidationRequest>,
) -> Result<HttpResponse, ApiError> {
    if !(2..=MAX_VALIDATION_SAMPLES).contains(&request.samples) {
        return Err(
            crate::error::Error::invalid("samples", format!("must be between 2 and {MAX_VALIDATION_SAMPLES}")).into()
        );
    }
    if state.store.metamodel_body(&id).await?.is_none() {
        return Err(ApiError::not_found("metamodel", &id));
    }
    let queued = ValidationJob { metamodel_id: id, samples: request.samples, seed: request.seed };
    let text = serde_json::to_string(&queued).expect("a job serialises");
    accept_job(&state, &headers, "validations", OperationKind::Validation, text).await
}
