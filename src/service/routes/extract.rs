//! Extractors whose rejections are problem+json: a JSON object body and query parameters.

use crate::service::AppState;
use crate::service::error::ApiError;
use axum::body::Bytes;
use axum::extract::rejection::QueryRejection;
use axum::extract::{FromRequest, FromRequestParts, Request};
use axum::http::StatusCode;
use axum::http::request::Parts;
use futures_util::StreamExt;
use serde::de::DeserializeOwned;
use std::time::Duration;

/// A JSON object body whose rejections (malformed, wrong types, not an object, wrong content type,
/// too large) are problem+json. Every request type is an object whose fields all have defaults,
/// and serde would read an array as such a struct, so anything but an object is refused first.
pub struct ApiJson<T>(pub T);

impl<T: DeserializeOwned> FromRequest<AppState> for ApiJson<T> {
    type Rejection = ApiError;

    async fn from_request(request: Request, state: &AppState) -> Result<Self, Self::Rejection> {
        if !json_content_type(request.headers()) {
            return Err(ApiError::new(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "Unsupported media type",
                "expected a body with `Content-Type: application/json`",
            ));
        }
        let bytes = body_within(request, state.config.max_body_bytes).await?;
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

/// How much of an oversized body is read and discarded before the 413 is sent, and for how long.
/// A server that answers while the client is still sending, then closes, makes the client's next
/// write fail ("broken pipe") before it reads the answer; reading the rest first lets the client
/// finish sending and read the 413. Past either bound the connection is closed anyway.
const DRAIN_BYTES: u64 = 1 << 30;
const DRAIN_TIME: Duration = Duration::from_secs(30);

/// The request's body, read whole if it has at most `limit` bytes; otherwise 413 problem+json,
/// sent once the rest of the body was read and discarded (within [`DRAIN_BYTES`] and
/// [`DRAIN_TIME`]), or at once when the client waits for `100 Continue` before sending it.
async fn body_within(request: Request, limit: usize) -> Result<Bytes, ApiError> {
    let declared = request
        .headers()
        .get(axum::http::header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok());
    let expects_continue = request
        .headers()
        .get(axum::http::header::EXPECT)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.eq_ignore_ascii_case("100-continue"));
    let too_large = || {
        ApiError::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            "Request body too large",
            format!("the body must have at most {limit} bytes"),
        )
    };
    if declared.is_some_and(|length| length > limit as u64) && expects_continue {
        // Not polling the body keeps hyper from sending `100 Continue`: the client never sends it.
        return Err(too_large());
    }
    let mut stream = request.into_body().into_data_stream();
    let mut body = Vec::with_capacity(declared.map_or(0, |length| length.min(limit as u64) as usize));
    while let Some(chunk) = stream.next().await {
        let chunk =
            chunk.map_err(|e| ApiError::new(StatusCode::BAD_REQUEST, "Unreadable request body", e.to_string()))?;
        if body.len() + chunk.len() > limit {
            let mut drained = (body.len() + chunk.len()) as u64;
            drop(body);
            let _ = tokio::time::timeout(DRAIN_TIME, async {
                while drained < DRAIN_BYTES
                    && let Some(Ok(chunk)) = stream.next().await
                {
                    drained += chunk.len() as u64;
                }
            })
            .await;
            return Err(too_large());
        }
        body.extend_from_slice(&chunk);
    }
    Ok(Bytes::from(body))
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
