//! Errors over HTTP: RFC 9457 problem+json naming the field at fault. Internal errors are logged
//! with the request and never echoed.

use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};

#[derive(Debug)]
pub struct ApiError {
    pub status: StatusCode,
    pub title: &'static str,
    pub detail: String,
    pub field: Option<String>,
    /// Seconds after which a retry may succeed (sent as `Retry-After`).
    pub retry_after: Option<u64>,
}

impl ApiError {
    pub fn new(status: StatusCode, title: &'static str, detail: impl Into<String>) -> Self {
        ApiError { status, title, detail: detail.into(), field: None, retry_after: None }
    }

    pub fn not_found(what: &str, id: &str) -> Self {
        ApiError::new(StatusCode::NOT_FOUND, "Not found", format!("no {what} with id `{id}`"))
    }

    /// The server cannot take the request now (full queue); the client should retry later.
    pub fn unavailable(detail: impl Into<String>, retry_after_s: u64) -> Self {
        ApiError {
            retry_after: Some(retry_after_s),
            ..ApiError::new(StatusCode::SERVICE_UNAVAILABLE, "Unavailable", detail)
        }
    }

    pub fn internal(error: impl std::fmt::Display) -> Self {
        tracing::error!(%error, "internal error");
        ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "Internal error", "the server failed; the error is logged")
    }
}

impl From<crate::error::Error> for ApiError {
    fn from(error: crate::error::Error) -> Self {
        match error {
            crate::error::Error::Invalid { field, reason } => ApiError {
                status: StatusCode::UNPROCESSABLE_ENTITY,
                title: "Invalid request",
                detail: format!("{field}: {reason}"),
                field: Some(field),
                retry_after: None,
            },
            crate::error::Error::Numerical(message) => {
                ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, "Numerical failure", message)
            }
            crate::error::Error::Cancelled => {
                ApiError::new(StatusCode::CONFLICT, "Cancelled", "the work was cancelled")
            }
            crate::error::Error::Internal(message) => ApiError::internal(message),
        }
    }
}

/// How long a client should wait before asking again while the database does not answer (s).
const DATABASE_RETRY_S: u64 = 2;

impl From<sqlx::Error> for ApiError {
    /// A database that cannot be reached now (restarting, unreachable, locked) is 503 with
    /// `Retry-After`, since the same request will succeed once it answers; any other database
    /// error is the server's failure.
    fn from(error: sqlx::Error) -> Self {
        if database_unreachable(&error) {
            tracing::warn!(%error, "the database does not answer");
            return ApiError::unavailable("the database does not answer now; try again shortly", DATABASE_RETRY_S);
        }
        ApiError::internal(error)
    }
}

/// Errors of reaching the database rather than of the statement: a refused, broken or timed-out
/// connection, a pool with none to give, PostgreSQL's connection exceptions (class 08) and its
/// shutdown and start-up (57P01-57P03), SQLite's file busy or locked past its busy timeout.
fn database_unreachable(error: &sqlx::Error) -> bool {
    match error {
        sqlx::Error::Io(_) | sqlx::Error::Tls(_) | sqlx::Error::PoolTimedOut | sqlx::Error::PoolClosed => true,
        sqlx::Error::WorkerCrashed => true,
        sqlx::Error::Database(error) => match error.code().as_deref() {
            Some(code) if code.starts_with("08") || ["57P01", "57P02", "57P03"].contains(&code) => true,
            Some(code) => code.parse::<i32>().is_ok_and(|sqlite| matches!(sqlite & 0xff, 5 | 6)),
            None => false,
        },
        _ => false,
    }
}

impl From<axum::extract::rejection::JsonRejection> for ApiError {
    fn from(rejection: axum::extract::rejection::JsonRejection) -> Self {
        ApiError::new(rejection.status(), "Malformed request body", rejection.body_text())
    }
}

/// An error as sent: RFC 9457 problem details (`application/problem+json`).
#[derive(Debug, Serialize, Deserialize, utoipa::ToSchema)]
pub struct ProblemDetails {
    /// Always `about:blank`: the status and title say what happened.
    #[serde(rename = "type")]
    pub kind: String,
    pub title: String,
    pub status: u16,
    /// What was wrong, for a person.
    pub detail: String,
    /// The fields at fault, when the request was well-formed but not acceptable.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub errors: Vec<FieldError>,
}

/// One field at fault, named as in the request (`inputs.wind_speed`, `samples`, …).
#[derive(Debug, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FieldError {
    pub field: String,
    pub detail: String,
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let errors = self.field.map(|field| FieldError { field, detail: self.detail.clone() }).into_iter().collect();
        let body = ProblemDetails {
            kind: "about:blank".into(),
            title: self.title.into(),
            status: self.status.as_u16(),
            detail: self.detail,
            errors,
        };
        let text = serde_json::to_string(&body).expect("problem details serialise");
        let mut response = (self.status, [(header::CONTENT_TYPE, "application/problem+json")], text).into_response();
        if let Some(seconds) = self.retry_after {
            response.headers_mut().insert(header::RETRY_AFTER, seconds.into());
        }
        // A body too large may not have been read to its end: the connection cannot carry another
        // request, and the client is told so.
        if self.status == StatusCode::PAYLOAD_TOO_LARGE {
            response.headers_mut().insert(header::CONNECTION, header::HeaderValue::from_static("close"));
        }
        response
    }
}
