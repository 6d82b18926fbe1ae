//! Liveness and readiness.

use crate::service::AppState;
use axum::Json;
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;
use std::sync::atomic::Ordering;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new().routes(routes!(healthz)).routes(routes!(readyz))
}

#[derive(Debug, Serialize, ToSchema)]
pub struct Health {
    /// `ok`, `ready`, `draining` or `database unreachable`.
    pub status: String,
}

fn health(status: &str) -> Json<Health> {
    Json(Health { status: status.into() })
}

/// The process answers; touches nothing else.
#[utoipa::path(get, path = "/healthz", tag = "health",
    responses((status = 200, description = "Alive", body = Health)))]
async fn healthz() -> Json<Health> {
    health("ok")
}

/// The store answers (its tables, not only the connection) and the server is not draining.
#[utoipa::path(get, path = "/readyz", tag = "health",
    responses(
        (status = 200, description = "Ready", body = Health),
        (status = 503, description = "Draining, or the database does not answer", body = Health,
            headers(("Retry-After" = u64, description = "Seconds before asking again"))),
    ))]
async fn readyz(State(state): State<AppState>) -> Response {
    let status = if state.draining.load(Ordering::Relaxed) {
        "draining"
    } else if !state.store.ping().await {
        "database unreachable"
    } else {
        return health("ready").into_response();
    };
    (StatusCode::SERVICE_UNAVAILABLE, [(header::RETRY_AFTER, "5")], health(status)).into_response()
}
