//! Stored metamodels, and the exceedance curves sampled from them.

use super::{ApiJson, Page};
use crate::analysis::{
    Response, automatic_thresholds, check_confidence, exceedance_curve, exceedance_svg, metamodel_peaks,
};
use crate::problem::Problem;
use crate::service::error::ApiError;
use crate::service::{AppState, MAX_VALIDATION_SAMPLES, ValidationJob, ValidationRequest};
use crate::surrogate::{Metamodel, Silent};
use axum::extract::{Path, Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response as HttpResponse};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::sync::Arc;

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/v1/metamodels", get(list))
        .route("/v1/metamodels/{id}", get(one).delete(remove))
        .route("/v1/metamodels/{id}/exceedance", post(exceedance))
        .route("/v1/metamodels/{id}/validations", post(start_validation))
}

async fn list(State(state): State<AppState>, Query(page): Query<Page>) -> Result<Json<Value>, ApiError> {
    page.check()?;
    let rows = state.store.metamodels(page.limit, page.offset).await?;
    let items: Vec<Value> = rows
        .iter()
        .map(|r| json!({"id": r.id, "operation_id": r.job_id, "preset": r.preset, "created_at_ms": r.created_at}))
        .collect();
    Ok(Json(json!({"metamodels": items, "limit": page.limit, "offset": page.offset})))
}

/// The full metamodel: coefficients and diagnostics, enough to reproduce predictions elsewhere.
async fn one(State(state): State<AppState>, Path(id): Path<String>) -> Result<HttpResponse, ApiError> {
    let body = state.store.metamodel_body(&id).await?.ok_or_else(|| ApiError::not_found("metamodel", &id))?;
    Ok(([(header::CONTENT_TYPE, "application/json")], body).into_response())
}

async fn remove(State(state): State<AppState>, Path(id): Path<String>) -> Result<StatusCode, ApiError> {
    if !state.store.delete_metamodel(&id).await? {
        return Err(ApiError::not_found("metamodel", &id));
    }
    state.loaded.lock().expect("cache lock").remove(&id);
    Ok(StatusCode::NO_CONTENT)
}

async fn load(state: &AppState, id: &str) -> Result<crate::service::Loaded, ApiError> {
    if let Some(found) = state.loaded.lock().expect("cache lock").get(id) {
        return Ok(found.clone());
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
    state.loaded.lock().expect("cache lock").insert(id.to_string(), loaded.clone());
    Ok(loaded)
}

#[derive(Debug, Clone, Copy, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
enum ResponseKind {
    #[default]
    Displacement,
    Drift,
}

#[derive(Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct ExceedanceRequest {
    samples: usize,
    seed: u64,
    /// Floor (1-based); the roof when absent.
    floor: Option<usize>,
    response: ResponseKind,
    thresholds: Option<Vec<f64>>,
    /// Inputs held fixed, by name.
    fixed: BTreeMap<String, f64>,
    confidence: f64,
}

impl Default for ExceedanceRequest {
    fn default() -> Self {
        ExceedanceRequest {
            samples: 1000,
            seed: 1,
            floor: None,
            response: ResponseKind::Displacement,
            thresholds: None,
            fixed: BTreeMap::new(),
            confidence: 0.95,
        }
    }
}

/// The curve with its band, as JSON, CSV or SVG by `Accept`.
async fn exceedance(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<ExceedanceRequest>,
) -> Result<HttpResponse, ApiError> {
    if request.samples == 0 || request.samples > state.config.max_samples {
        return Err(crate::error::Error::invalid(
            "samples",
            format!("must be between 1 and {}", state.config.max_samples),
        )
        .into());
    }
    check_confidence(request.confidence)?;
    if let Some(t) = &request.thresholds
        && (t.is_empty() || t.len() > 10_000 || t.iter().any(|x| !x.is_finite()))
    {
        return Err(crate::error::Error::invalid("thresholds", "must be 1 to 10000 finite numbers").into());
    }
    let loaded = load(&state, &id).await?;
    let accept = headers.get(header::ACCEPT).and_then(|v| v.to_str().ok()).unwrap_or("application/json").to_string();
    let curve = tokio::task::spawn_blocking(
        move || -> crate::error::Result<(Value, crate::analysis::ExceedanceCurve, String)> {
            let (metamodel, problem) = loaded.as_ref();
            let floor = request.floor.unwrap_or(problem.structure.floors());
            let response = match request.response {
                ResponseKind::Displacement => Response::Displacement { floor },
                ResponseKind::Drift => Response::Drift { floor },
            };
            let mut inputs = problem.inputs.clone();
            for (name, value) in &request.fixed {
                inputs = inputs.with_fixed(name, *value)?;
            }
            let peaks = metamodel_peaks(metamodel, problem, &inputs, request.samples, request.seed, response, &Silent)?;
            let thresholds = request.thresholds.clone().unwrap_or_else(|| automatic_thresholds(&peaks, 50));
            let curve = exceedance_curve(&peaks, &thresholds, request.confidence);
            let label = format!("{response:?}");
            Ok((serde_json::to_value(response).expect("a response serialises"), curve, label))
        },
    )
    .await
    .map_err(ApiError::internal)??;
    let (response, curve, label) = curve;
    if accept.contains("text/csv") {
        let mut text = String::from("threshold_m,probability,lower,upper\n");
        for i in 0..curve.thresholds.len() {
            text +=
                &format!("{},{},{},{}\n", curve.thresholds[i], curve.probabilities[i], curve.lower[i], curve.upper[i]);
        }
        return Ok(([(header::CONTENT_TYPE, "text/csv")], text).into_response());
    }
    if accept.contains("image/svg+xml") {
        let svg = exceedance_svg(&[("PC-NARX", &curve)], &format!("peak {label} x (m)"));
        return Ok(([(header::CONTENT_TYPE, "image/svg+xml")], svg).into_response());
    }
    let mut body = serde_json::to_value(&curve).expect("a curve serialises");
    body["response"] = response;
    body["metamodel_id"] = json!(id);
    Ok(Json(body).into_response())
}

/// Queues a validation of the metamodel against the reference on fresh samples (an operation).
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
    super::accept_job(&state, &headers, "validations", "validation", text).await
}
