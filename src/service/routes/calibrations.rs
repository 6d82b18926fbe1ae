//! Starting calibrations: checked at once, then queued as an operation.

use super::{ApiJson, accept_job};
use crate::service::error::{ApiError, ProblemDetails};
use crate::service::routes::operations::Operation;
use crate::service::work::Job;
use crate::service::{AppState, CalibrationRequest};
use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Response;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new().routes(routes!(start_calibration))
}

/// Starts a calibration: K reference storms on a Latin hypercube, then the PC-NARX fit. Every field
/// is optional (the paper's study by default); a bad spec is refused now, not in the worker.
#[utoipa::path(post, path = "/v1/calibrations", tag = "calibrations",
    request_body = CalibrationRequest,
    params(("Idempotency-Key" = Option<String>, Header, pattern = "^[!-~]{1,255}$", description = "Makes a retry return the same operation")),
    responses(
        (status = 202, description = "Queued; follow `Location`", body = Operation,
            headers(("Location" = String, description = "The operation"), ("Retry-After" = u64, description = "Seconds before polling"))),
        (status = 422, description = "A field is invalid (named in `errors`), a combination of fields is (square matrices of one size, time and generation steps that resolve the cut-off, a storm within the wind's period, admissible marginals), the study exceeds the server's memory or storm-step budget, or the Idempotency-Key was used with another request", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 503, description = "The queue is full, or the database does not answer now", body = ProblemDetails, content_type = "application/problem+json",
            headers(("Retry-After" = u64, description = "Seconds before trying again"))),
    ))]
async fn start_calibration(
    State(state): State<AppState>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<CalibrationRequest>,
) -> Result<Response, ApiError> {
    // Resolving builds the study (an eigen-analysis, a spectral table): off the runtime.
    let (checked, config) = (request.clone(), state.config.clone());
    tokio::task::spawn_blocking(move || checked.resolve(&config).map(|_| ())).await.map_err(ApiError::internal)??;
    accept_job(&state, &headers, Job::Calibration(Box::new(request))).await
}
