//! Stored metamodels, the exceedance curves and demand samples drawn from them, and their
//! validation against the reference model.

use super::sampling::{SamplingResponses, Work, answer_now, answer_or_queue};
use super::{ApiJson, ApiQuery, Page, accept_job};
use crate::analysis::{OnThisMachine, held_inputs};
use crate::service::cache::Loaded;
use crate::service::demands::DemandsRequest;
use crate::service::error::{ApiError, ProblemDetails};
use crate::service::exceedance::{ExceedanceAnswer, ExceedanceJob, ExceedanceRequest};
use crate::service::routes::operations::Operation;
use crate::service::work::Job;
use crate::service::{AppState, MAX_VALIDATION_SAMPLES, ValidationJob, ValidationRequest};
use crate::surrogate::Metamodel;
use axum::Json;
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response as HttpResponse};
use serde::Serialize;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(list_metamodels))
        .routes(routes!(get_metamodel, delete_metamodel))
        .routes(routes!(exceedance_curve))
        .routes(routes!(start_validation))
        .routes(routes!(demand_sample))
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
    state.metamodels.forget(&id);
    Ok(StatusCode::NO_CONTENT)
}

/// A stored metamodel and its rebuilt study, from this replica's cache (see
/// [`MetamodelCache::for_request`](crate::service::cache::MetamodelCache::for_request)).
pub async fn load(state: &AppState, id: &str) -> Result<Loaded, ApiError> {
    state.metamodels.for_request(&state.store, id).await
}

/// The peak-response exceedance curve with its band, sampled from the metamodel: JSON, CSV or SVG
/// by `Accept`. Requests above the server's synchronous limit (or with `Prefer: respond-async`)
/// run as an operation whose `result` is the JSON curve.
#[utoipa::path(post, path = "/v1/metamodels/{id}/exceedance", tag = "metamodels",
    request_body = ExceedanceRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Prefer" = Option<String>, Header, description = "`respond-async` to run the request as an operation"),
        ("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry of an asynchronous request return the same operation"),
    ),
    responses(
        (status = 200, description = "The curve", content(
            (ExceedanceAnswer = "application/json"),
            (String = "text/csv", example = "threshold_m,probability,lower,upper\n0.31,1,0.996,1\n"),
            (String = "image/svg+xml"),
        )),
        SamplingResponses,
    ))]
async fn exceedance_curve(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<ExceedanceRequest>,
) -> Result<HttpResponse, ApiError> {
    request.check(&state.config)?;
    let loaded = load(&state, &id).await?;
    request.check_against(&loaded.study)?;
    // Reference storms take minutes: a certified curve is always an operation.
    let storms = if request.certify.is_some() { None } else { Some(request.samples) };
    let queued = {
        let (id, request) = (id.clone(), request.clone());
        move || Job::Exceedance(ExceedanceJob { metamodel_id: id, request })
    };
    let work: Work = Box::new(move |metamodel, study, observer, rendering| {
        // Certified requests are operations: here no reference storm runs.
        Ok(request.answer(metamodel, study, &id, &OnThisMachine, observer)?.render(rendering))
    });
    answer_or_queue(&state, &headers, loaded, storms, queued, work).await
}

/// Per storm at one wind speed, the peak acceleration of every floor (g) and the peak drift ratio of
/// every storey (rad), as pelicun reads a demand sample for FEMA P-58 loss assessment (a header
/// `,1-PFA-0-1,…,1-PID-1-1,…`, a `Units` row, a row per storm). Answered at once.
#[utoipa::path(post, path = "/v1/metamodels/{id}/demands", tag = "metamodels",
    request_body = DemandsRequest,
    params(("id" = String, Path, description = "Metamodel id")),
    responses(
        (status = 200, description = "The demand sample", content(
            (String = "text/csv", example = ",1-PFA-0-1,1-PFA-1-1,1-PID-1-1\nUnits,g,g,rad\n0,0e0,2.37e-3,1.1e-4\n"),
        )),
        (status = 404, description = "No such metamodel", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 422, description = "A field is invalid (named in `errors`), or a storm diverged", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn demand_sample(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<DemandsRequest>,
) -> Result<HttpResponse, ApiError> {
    request.check(&state.config)?;
    let loaded = load(&state, &id).await?;
    let work: Work =
        Box::new(move |metamodel, study, observer, _| Ok(("text/csv", request.answer(metamodel, study, observer)?)));
    answer_now(&state, &headers, loaded, work).await
}

/// Validates the metamodel against the reference model on fresh samples, as an operation whose
/// `result` is the comparison (correlation, errors, both curves).
#[utoipa::path(post, path = "/v1/metamodels/{id}/validations", tag = "metamodels",
    request_body = ValidationRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry return the same operation"),
    ),
    responses(
        (status = 202, description = "Queued; follow `Location`", body = Operation,
            headers(("Location" = String, description = "The operation"), ("Retry-After" = u64, description = "Seconds before polling"))),
        (status = 404, description = "No such metamodel", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 422, description = "A field is invalid (named in `errors`), or the Idempotency-Key was used with another request", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 503, description = "The queue is full, or the database does not answer now", body = ProblemDetails, content_type = "application/problem+json",
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
    let loaded = load(&state, &id).await?;
    let storm_steps = request.samples as f64 * loaded.study.storm.steps() as f64;
    if storm_steps > state.config.max_job_steps as f64 {
        return Err(crate::error::Error::invalid(
            "samples",
            format!(
                "samples × steps per storm = {storm_steps:.3e} reference storm steps exceeds this server's budget of {:.3e}",
                state.config.max_job_steps as f64
            ),
        )
        .into());
    }
    held_inputs(&loaded.study, &request.fixed)?;
    let queued = ValidationJob { metamodel_id: id, samples: request.samples, seed: request.seed, fixed: request.fixed };
    accept_job(&state, &headers, Job::Validation(queued)).await
}
