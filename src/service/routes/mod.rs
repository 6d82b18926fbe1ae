//! The routes, one router per resource, merged here with the layers every request passes.

mod auth;
mod calibrations;
mod health;
mod metamodels;
mod operations;
mod presets;
mod telemetry;

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
    let mut app = Router::new()
        .merge(health::router())
        .merge(telemetry::router())
        .merge(api)
        .route_layer(axum::middleware::from_fn(telemetry::track))
        .with_state(state.clone());
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

/// Queues a job and answers 202 with its `Location`, honouring `Idempotency-Key`: a retry with the
/// same body gets the same operation, a different body under the same key is refused (422).
pub async fn accept_job(
    state: &AppState,
    headers: &axum::http::HeaderMap,
    endpoint: &str,
    kind: &str,
    request: String,
) -> Result<axum::response::Response, super::error::ApiError> {
    use axum::http::{StatusCode, header};
    use axum::response::IntoResponse;
    let key = match headers.get("idempotency-key") {
        None => None,
        Some(v) => match v.to_str() {
            Ok(k) if !k.is_empty() && k.len() <= 255 => Some(k.to_string()),
            _ => {
                return Err(crate::error::Error::invalid(
                    "Idempotency-Key",
                    "must be 1 to 255 visible ASCII characters",
                )
                .into());
            }
        },
    };
    let mut id = uuid::Uuid::new_v4().to_string();
    let earlier = state.store.insert_job(&id, kind, &request, key.as_deref().map(|k| (k, endpoint))).await?;
    if let Some((operation, stored)) = earlier {
        if stored != request {
            return Err(
                crate::error::Error::invalid("Idempotency-Key", "was already used with a different request").into()
            );
        }
        id = operation;
    } else {
        state.wake.notify_one();
    }
    let row = state.store.job(&id).await?.ok_or_else(|| super::error::ApiError::internal("a queued job vanished"))?;
    Ok((
        StatusCode::ACCEPTED,
        [(header::LOCATION, format!("/v1/operations/{id}")), (header::RETRY_AFTER, "2".to_string())],
        axum::Json(operations::operation(&row)),
    )
        .into_response())
}
