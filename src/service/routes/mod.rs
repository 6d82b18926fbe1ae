//! The routes, one router per resource, merged here with the layers every request passes.

mod auth;
mod calibrations;
mod health;
mod metamodels;
mod operations;
mod presets;

use super::AppState;
use axum::Router;
use axum::extract::rejection::JsonRejection;
use axum::extract::{FromRequest, Request};
use serde::de::DeserializeOwned;
use tower_http::request_id::{MakeRequestUuid, PropagateRequestIdLayer, SetRequestIdLayer};
use tower_http::trace::TraceLayer;

pub fn router(state: AppState) -> Router {
    let limit = state.config.max_body_bytes;
    let api = Router::new()
        .merge(presets::router())
        .merge(calibrations::router())
        .merge(operations::router())
        .merge(metamodels::router())
        .layer(axum::middleware::from_fn_with_state(state.clone(), auth::require_api_key));
    let mut app = Router::new().merge(health::router()).merge(api).with_state(state.clone());
    if !state.config.cors_origins.is_empty() {
        app = app.layer(auth::cors(&state.config.cors_origins));
    }
    app
        // axum's limit, not tower-http's: its rejection reaches `ApiJson` and becomes problem+json.
        .layer(axum::extract::DefaultBodyLimit::max(limit))
        .layer(PropagateRequestIdLayer::x_request_id())
        .layer(TraceLayer::new_for_http())
        .layer(SetRequestIdLayer::x_request_id(MakeRequestUuid))
}

/// A JSON body whose rejections (malformed, wrong types, wrong content type) are problem+json.
pub struct ApiJson<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned> FromRequest<S> for ApiJson<T> {
    type Rejection = super::error::ApiError;

    async fn from_request(request: Request, state: &S) -> Result<Self, Self::Rejection> {
        match axum::Json::<T>::from_request(request, state).await {
            Ok(axum::Json(value)) => Ok(ApiJson(value)),
            Err(rejection) => Err(payload_error(rejection)),
        }
    }
}

fn payload_error(rejection: JsonRejection) -> super::error::ApiError {
    if rejection.status() == axum::http::StatusCode::PAYLOAD_TOO_LARGE {
        return super::error::ApiError::new(rejection.status(), "Request body too large", rejection.body_text());
    }
    rejection.into()
}

/// Pagination of lists: `?limit=&offset=`.
#[derive(Debug, serde::Deserialize)]
pub struct Page {
    #[serde(default = "default_limit")]
    pub limit: i64,
    #[serde(default)]
    pub offset: i64,
}

fn default_limit() -> i64 {
    50
}

impl Page {
    pub fn check(&self) -> Result<(), super::error::ApiError> {
        if !(1..=500).contains(&self.limit) || self.offset < 0 {
            return Err(super::error::ApiError::new(
                axum::http::StatusCode::UNPROCESSABLE_ENTITY,
                "Invalid request",
                "limit must be between 1 and 500 and offset non-negative",
            ));
        }
        Ok(())
    }
}
