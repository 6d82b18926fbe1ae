//! Annual curves, fragility curves and Sobol indices of a stored metamodel: answered at once when
//! small, as operations when large (see `sampling`).

use super::ApiJson;
use super::metamodels::load;
use super::operations::OperationKind;
use super::sampling::{Queued, SamplingResponses, Work, answer_or_queue};
use crate::analysis::OnThisMachine;
use crate::service::AppState;
use crate::service::analyses::{
    AnalysisAnswer, AnalysisJob, AnalysisRequest, FragilityRequest, HazardRequest, SensitivityRequest,
};
use crate::service::error::ApiError;
use axum::extract::{Path, State};
use axum::http::HeaderMap;
use axum::response::Response as HttpResponse;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new().routes(routes!(hazard)).routes(routes!(fragility)).routes(routes!(sensitivity))
}

/// Checks a request against the stored study and answers it or queues it.
async fn analyse(
    state: AppState,
    id: String,
    headers: HeaderMap,
    endpoint: &'static str,
    request: AnalysisRequest,
) -> Result<HttpResponse, ApiError> {
    let loaded = load(&state, &id).await?;
    request.check(&state.config, &loaded.1)?;
    // Reference storms take minutes: a certified answer is always an operation.
    let storms = (request.reference_storms() == 0).then(|| request.storms(&loaded.1));
    let queued = {
        let (id, request) = (id.clone(), request.clone());
        move || Queued {
            endpoint,
            kind: match request {
                AnalysisRequest::Hazard(_) => OperationKind::Hazard,
                AnalysisRequest::Fragility(_) => OperationKind::Fragility,
                AnalysisRequest::Sensitivity(_) => OperationKind::Sensitivity,
            },
            job: serde_json::to_string(&AnalysisJob { metamodel_id: id, request }).expect("a job serialises"),
        }
    };
    let work: Work = Box::new(move |metamodel, study, observer, rendering| {
        // Certified requests are operations: here no reference storm runs.
        Ok(request.answer(metamodel, study, &id, &OnThisMachine, observer)?.render(rendering))
    });
    answer_or_queue(&state, &headers, loaded, storms, queued, work).await
}

/// The annual exceedance curve of a peak response under a wind climate, with its band, return
/// levels and, at `limit`, the reliability index: JSON, CSV or SVG by `Accept`. Requests of more
/// storms than the server's synchronous limit (or with `Prefer: respond-async`) run as an
/// operation whose `result` is the JSON answer.
#[utoipa::path(post, path = "/v1/metamodels/{id}/hazard", tag = "analyses",
    request_body = HazardRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Prefer" = Option<String>, Header, description = "`respond-async` to run the request as an operation"),
        ("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry of an asynchronous request return the same operation"),
    ),
    responses(
        (status = 200, description = "The annual curve", content(
            (AnalysisAnswer = "application/json"),
            (String = "text/csv", example = "threshold_m,annual_probability,lower,upper,cov,mri_years,beyond_calibrated_range\n0.6,0.1,0.09,0.11,0.03,10,0\n"),
            (String = "image/svg+xml"),
        )),
        SamplingResponses,
    ))]
async fn hazard(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<HazardRequest>,
) -> Result<HttpResponse, ApiError> {
    analyse(state, id, headers, "hazard", AnalysisRequest::Hazard(request)).await
}

/// Fragility curves P(peak > x | v) over storm speeds with their bands and lognormal fits: JSON or
/// SVG by `Accept`; large requests run as an operation.
#[utoipa::path(post, path = "/v1/metamodels/{id}/fragility", tag = "analyses",
    request_body = FragilityRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Prefer" = Option<String>, Header, description = "`respond-async` to run the request as an operation"),
        ("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry of an asynchronous request return the same operation"),
    ),
    responses(
        (status = 200, description = "The fragility curves", content(
            (AnalysisAnswer = "application/json"),
            (String = "image/svg+xml"),
        )),
        SamplingResponses,
    ))]
async fn fragility(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<FragilityRequest>,
) -> Result<HttpResponse, ApiError> {
    analyse(state, id, headers, "fragility", AnalysisRequest::Fragility(request)).await
}

/// First-order and total Sobol indices of a peak response for every random input and the storm's
/// phases (`storm`), with bootstrap intervals; large requests run as an operation.
#[utoipa::path(post, path = "/v1/metamodels/{id}/sensitivity", tag = "analyses",
    request_body = SensitivityRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Prefer" = Option<String>, Header, description = "`respond-async` to run the request as an operation"),
        ("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry of an asynchronous request return the same operation"),
    ),
    responses(
        (status = 200, description = "The indices", body = AnalysisAnswer),
        SamplingResponses,
    ))]
async fn sensitivity(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<SensitivityRequest>,
) -> Result<HttpResponse, ApiError> {
    analyse(state, id, headers, "sensitivity", AnalysisRequest::Sensitivity(request)).await
}
