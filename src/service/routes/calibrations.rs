//! Starting calibrations: checked at once, then queued as an operation.

use super::{ApiJson, accept_job};
use crate::service::error::ApiError;
use crate::service::{AppState, CalibrationRequest};
use axum::Router;
use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Response;
use axum::routing::post;

pub fn router() -> Router<AppState> {
    Router::new().route("/v1/calibrations", post(start))
}

/// 202 with the operation's `Location`; bad specs are refused now, not in the worker.
async fn start(
    State(state): State<AppState>,
    headers: HeaderMap,
    ApiJson(request): ApiJson<CalibrationRequest>,
) -> Result<Response, ApiError> {
    request.resolve(&state.config)?;
    let text = serde_json::to_string(&request).expect("a request serialises");
    accept_job(&state, &headers, "calibrations", "calibration", text).await
}
