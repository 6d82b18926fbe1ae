//! Annual curves, fragility curves, Sobol indices, serviceability checks and sweeps of a stored
//! metamodel: answered at once when
//! small, as operations when large (see `sampling`).

use super::ApiJson;
use super::metamodels::load;
use super::sampling::{SamplingResponses, Work, answer_or_queue};
use crate::analysis::OnThisMachine;
use crate::service::AppState;
use crate::service::analyses::{AnalysisAnswer, AnalysisRequest, FragilityRequest, HazardRequest, SensitivityRequest};
use crate::service::checks::{ServiceabilityRequest, SweepRequest};
use crate::service::error::ApiError;
use crate::service::work::Job;
use axum::extract::{Path, State};
use axum::http::HeaderMap;
use axum::response::Response as HttpResponse;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(hazard))
        .routes(routes!(fragility))
        .routes(routes!(sensitivity))
        .routes(routes!(serviceability))
        .routes(routes!(sweep))
}

/// Checks a request against the stored study and answers it or queues it.
async fn analyse(
    state: AppState,
    id: String,
    headers: HeaderMap,
    request: AnalysisRequest,
) -> Result<HttpResponse, ApiError> {
    let loaded = load(&state, &id).await?;
    request.check(&state.config, &loaded.study)?;
    // Reference storms take minutes: a certified answer is always an operation.
    let storms = (request.reference_storms() == 0).then(|| request.storms(&loaded.study));
    let queued = {
        let (id, request) = (id.clone(), request.clone());
        move || Job::analysis(id, request)
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
    analyse(state, id, headers, AnalysisRequest::Hazard(request)).await
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
    analyse(state, id, headers, AnalysisRequest::Fragility(request)).await
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
    analyse(state, id, headers, AnalysisRequest::Sensitivity(request)).await
}

/// Criteria of comfort, drift and strength judged together under a site's climate: for each, the
/// T-year level at every judged floor from the same storms, the governing floor, the band, the
/// utilisation and a verdict (`pass` where every band's upper end is within the limit, `fail`
/// where some lower end is beyond); a strength criterion's annual probability and β against
/// ASCE 7's target. JSON, CSV or SVG (the profiles over their limits) by `Accept`; large requests
/// run as an operation.
#[utoipa::path(post, path = "/v1/metamodels/{id}/serviceability", tag = "analyses",
    request_body = ServiceabilityRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Prefer" = Option<String>, Header, description = "`respond-async` to run the request as an operation"),
        ("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry of an asynchronous request return the same operation"),
    ),
    responses(
        (status = 200, description = "The verdicts", content(
            (AnalysisAnswer = "application/json"),
            (String = "text/csv", example = "criterion,response,statistic,unit,return_period_years,floor,value,lower,upper,limit,utilisation,governing,verdict\nnbcc-office,acceleration,peak,m/s²,10,40,0.2,0.19,0.21,0.245,0.82,true,pass\n"),
            (String = "image/svg+xml"),
        )),
        SamplingResponses,
    ))]
async fn serviceability(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<ServiceabilityRequest>,
) -> Result<HttpResponse, ApiError> {
    analyse(state, id, headers, AnalysisRequest::Serviceability(request)).await
}

/// The T-year level of a response with one input held at each of several values, every other input
/// random and the same storms at every value: how a damper is sized against a limit. JSON, CSV or
/// SVG by `Accept`; large requests run as an operation.
#[utoipa::path(post, path = "/v1/metamodels/{id}/sweep", tag = "analyses",
    request_body = SweepRequest,
    params(
        ("id" = String, Path, description = "Metamodel id"),
        ("Prefer" = Option<String>, Header, description = "`respond-async` to run the request as an operation"),
        ("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry of an asynchronous request return the same operation"),
    ),
    responses(
        (status = 200, description = "The level at each value", content(
            (AnalysisAnswer = "application/json"),
            (String = "text/csv", example = "damper_c4,level_m_s2,lower,upper\n0,0.41,0.40,0.42\n"),
            (String = "image/svg+xml"),
        )),
        SamplingResponses,
    ))]
async fn sweep(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<SweepRequest>,
) -> Result<HttpResponse, ApiError> {
    analyse(state, id, headers, AnalysisRequest::Sweep(request)).await
}
