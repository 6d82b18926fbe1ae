//! The routes, one router per resource, merged here with the layers every request passes.

mod analyses;
mod auth;
mod calibrations;
mod extract;
mod health;
pub mod metamodels;
mod openapi;
pub mod operations;
mod page;
mod pagination;
mod presets;
mod queue;
mod sampling;
mod study;
mod telemetry;

pub use auth::ApiKeys;
pub use openapi::{openapi, openapi_for};

use super::error::ApiError;
use super::{AppState, Role};
use axum::Router;
use extract::{ApiJson, ApiQuery};
use pagination::Page;
use queue::accept_job;
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
        .layer(TraceLayer::new_for_http().make_span_with(request_span))
        .layer(SetRequestIdLayer::x_request_id(MakeRequestUuid))
}

/// Every request's span carries its `X-Request-Id` (the client's, or one made for it), so that
/// what a request logged, and the job it queued, can be found by the id its client was sent.
fn request_span<B>(request: &axum::http::Request<B>) -> tracing::Span {
    let id = request.headers().get("x-request-id").and_then(|v| v.to_str().ok()).unwrap_or("none");
    tracing::info_span!("request", id, method = %request.method(), uri = %request.uri())
}
