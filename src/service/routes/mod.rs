//! The routes, one router per resource, merged here with the layers every request passes.

mod analyses;
mod auth;
mod calibrations;
mod health;
pub mod metamodels;
mod openapi;
pub mod operations;
mod page;
mod presets;
mod sampling;
mod study;
mod telemetry;

pub use auth::ApiKeys;
pub use openapi::{openapi, openapi_for};

use super::error::ApiError;
use super::{AppState, Role};
use crate::service::store::Enqueued;
use axum::Router;
use axum::body::Bytes;
use axum::extract::rejection::QueryRejection;
use axum::extract::{FromRequest, FromRequestParts, Request};
use axum::http::StatusCode;
use axum::http::request::Parts;
use operations::OperationKind;
use serde::de::DeserializeOwned;
use std::sync::Arc;
use tower_http::request_id::{MakeRequestUuid, PropagateRequestIdLayer, SetRequestIdLayer};
use tower_http::trace::TraceLayer;
use utoipa_axum::router::OpenApiRouter;

/// Every documented route, with its documentation.
fn documented() -> OpenApiRouter<AppState> {
    OpenApiRouter::with_openapi(openapi::base())
        .merge(health::router())
        .merge(telemetry::router())
        .merge(presets::router())
        .merge(calibrations::router())
        .merge(operations::router())
        .merge(metamodels::router())
        .merge(study::router())
        .merge(analyses::router())
}

pub fn router(state: AppState) -> Router {
    let limit = state.config.max_body_bytes;
    let served = match state.config.role {
        Role::All | Role::Api => documented(),
        Role::Worker => OpenApiRouter::with_openapi(openapi::base()).merge(health::router()).merge(telemetry::router()),
    };
    let (mut routes, mut spec) = served.split_for_parts();
    if state.config.role != Role::Worker {
        routes = routes.merge(page::router());
    }
    openapi::add_shared_responses(&mut spec);
    openapi::state_configured_limits(&mut spec, &state.config);
    let spec = Arc::new(spec.to_pretty_json().expect("the OpenAPI document serialises"));
    let mut app = routes
        .route(
            "/openapi.json",
            axum::routing::get(move || async move {
                ([(axum::http::header::CONTENT_TYPE, "application/json")], (*spec).clone())
            }),
        )
        .fallback(|| async { ApiError::new(axum::http::StatusCode::NOT_FOUND, "Not found", "no such route") })
        .route_layer(axum::middleware::from_fn_with_state(state.clone(), auth::require_api_key))
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

/// A JSON object body whose rejections (malformed, wrong types, not an object, wrong content type,
/// too large) are problem+json. Every request type is an object whose fields all have defaults,
/// and serde would read an array as such a struct, so anything but an object is refused first.
pub struct ApiJson<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned> FromRequest<S> for ApiJson<T> {
    type Rejection = super::error::ApiError;

    async fn from_request(request: Request, state: &S) -> Result<Self, Self::Rejection> {
        if !json_content_type(request.headers()) {
            return Err(ApiError::new(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "Unsupported media type",
                "expected a body with `Content-Type: application/json`",
            ));
        }
        let bytes = Bytes::from_request(request, state).await.map_err(|rejection| {
            let title = if rejection.status() == StatusCode::PAYLOAD_TOO_LARGE {
                "Request body too large"
            } else {
                "Unreadable request body"
            };
            ApiError::new(rejection.status(), title, rejection.body_text())
        })?;
        let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
        if first != Some(&b'{') {
            return Err(match serde_json::from_slice::<serde_json::Value>(&bytes) {
                Ok(value) => crate::error::Error::invalid(
                    "body",
                    format!("must be a JSON object, got {}", json_type_name(&value)),
                )
                .into(),
                Err(error) => ApiError::new(StatusCode::BAD_REQUEST, "Malformed request body", error.to_string()),
            });
        }
        axum::Json::<T>::from_bytes(&bytes).map(|axum::Json(value)| ApiJson(value)).map_err(ApiError::from)
    }
}

/// `application/json`, or any `application/…+json`, with or without parameters.
fn json_content_type(headers: &axum::http::HeaderMap) -> bool {
    let Some(value) = headers.get(axum::http::header::CONTENT_TYPE).and_then(|v| v.to_str().ok()) else {
        return false;
    };
    let essence = value.split(';').next().unwrap_or("").trim().to_ascii_lowercase();
    essence == "application/json" || (essence.starts_with("application/") && essence.ends_with("+json"))
}

fn json_type_name(value: &serde_json::Value) -> &'static str {
    match value {
        serde_json::Value::Null => "null",
        serde_json::Value::Bool(_) => "a boolean",
        serde_json::Value::Number(_) => "a number",
        serde_json::Value::String(_) => "a string",
        serde_json::Value::Array(_) => "an array",
        serde_json::Value::Object(_) => "an object",
    }
}

/// Query parameters whose rejection (a value of the wrong type) is problem+json.
pub struct ApiQuery<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned> FromRequestParts<S> for ApiQuery<T> {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, Self::Rejection> {
        match axum::extract::Query::<T>::from_request_parts(parts, state).await {
            Ok(axum::extract::Query(value)) => Ok(ApiQuery(value)),
            Err(rejection) => Err(query_error(rejection)),
        }
    }
}

fn query_error(rejection: QueryRejection) -> ApiError {
    ApiError::new(rejection.status(), "Malformed query", rejection.body_text())
}

/// Pagination of lists: `?limit=&offset=`.
#[derive(Debug, serde::Deserialize, utoipa::IntoParams)]
#[into_params(parameter_in = Query)]
pub struct Page {
    /// Items per page, 1 to 500.
    #[serde(default = "default_limit")]
    #[param(minimum = 1, maximum = 500, default = 50)]
    pub limit: i64,
    /// Items to skip.
    #[serde(default)]
    #[param(minimum = 0, default = 0)]
    pub offset: i64,
}

fn default_limit() -> i64 {
    50
}

impl Page {
    pub fn check(&self) -> Result<(), ApiError> {
        if !(1..=500).contains(&self.limit) {
            return Err(crate::error::Error::invalid("limit", "must be between 1 and 500").into());
        }
        if self.offset < 0 {
            return Err(crate::error::Error::invalid("offset", "must not be negative").into());
        }
        Ok(())
    }
}

/// How long a client should wait before offering work to a full queue again (s).
const QUEUE_FULL_RETRY_S: u64 = 30;

/// Queues a job and answers 202 with its `Location`, honouring `Idempotency-Key`: a retry with the
/// same body gets the same operation, a different body under the same key is refused (422). A
/// full queue is 503 with `Retry-After`.
pub async fn accept_job(
    state: &AppState,
    headers: &axum::http::HeaderMap,
    endpoint: &str,
    kind: OperationKind,
    request: String,
) -> Result<axum::response::Response, ApiError> {
    use axum::http::{StatusCode, header};
    use axum::response::IntoResponse;
    let key = match headers.get("idempotency-key") {
        None => None,
        Some(v) if (1..=255).contains(&v.len()) && v.as_bytes().iter().all(u8::is_ascii_graphic) => {
            Some(String::from_utf8_lossy(v.as_bytes()).into_owned())
        }
        Some(_) => {
            return Err(crate::error::Error::invalid(
                "Idempotency-Key",
                "must be 1 to 255 visible ASCII characters without spaces",
            )
            .into());
        }
    };
    let new_id = uuid::Uuid::new_v4().to_string();
    let idempotency = key.as_deref().map(|k| (k, endpoint));
    let max_queued = state.config.max_queued_jobs as i64;
    let keys_since = state.config.idempotency_keys_since_ms();
    let id = match state.store.insert_job(&new_id, kind.as_str(), &request, idempotency, keys_since, max_queued).await?
    {
        Enqueued::New => {
            state.wake.notify_one();
            new_id
        }
        Enqueued::Earlier { id, request: stored } if stored == request => id,
        Enqueued::Earlier { .. } => {
            return Err(
                crate::error::Error::invalid("Idempotency-Key", "was already used with a different request").into()
            );
        }
        Enqueued::QueueFull => {
            return Err(ApiError::unavailable(
                format!("{} jobs are waiting already; try again later", state.config.max_queued_jobs),
                QUEUE_FULL_RETRY_S,
            ));
        }
    };
    let row = state.store.job(&id).await?.ok_or_else(|| ApiError::internal("a queued job vanished"))?;
    Ok((
        StatusCode::ACCEPTED,
        [(header::LOCATION, format!("/v1/operations/{id}")), (header::RETRY_AFTER, "2".to_string())],
        axum::Json(operations::operation(&row)?),
    )
        .into_response())
}
