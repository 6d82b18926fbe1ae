//! Optional bearer API keys and the CORS allow-list.

use crate::error::{Error, Result};
use crate::service::AppState;
use crate::service::error::ApiError;
use axum::extract::{Request, State};
use axum::http::{HeaderName, HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use sha2::{Digest, Sha256};
use tower_http::cors::{AllowOrigin, CorsLayer};

/// The configured API keys, kept as SHA-256 digests: a presented key is hashed and compared with
/// every digest without an early exit, so the time a check takes reveals neither how much of a key
/// matched nor its length, nor which key it was.
#[derive(Debug, Clone, Default)]
pub struct ApiKeys {
    digests: Vec<[u8; 32]>,
}

impl ApiKeys {
    /// Refuses an empty or blank key (a trailing comma in `WINDMETA_API_KEYS` makes one, and an
    /// empty key would match a request without `Authorization`), and keys with surrounding
    /// whitespace or characters a header cannot carry.
    pub fn new(keys: &[String]) -> Result<ApiKeys> {
        let mut digests = Vec::with_capacity(keys.len());
        for (i, key) in keys.iter().enumerate() {
            let field = format!("api_keys[{i}]");
            if key.trim().is_empty() {
                return Err(Error::invalid(
                    field,
                    "is empty or blank (is there a stray comma in --api-keys / WINDMETA_API_KEYS?)",
                ));
            }
            if key.trim() != key || !key.bytes().all(|b| b.is_ascii_graphic()) {
                return Err(Error::invalid(field, "must be visible ASCII characters without spaces"));
            }
            digests.push(Sha256::digest(key.as_bytes()).into());
        }
        Ok(ApiKeys { digests })
    }

    /// Whether requests need a key at all.
    pub fn required(&self) -> bool {
        !self.digests.is_empty()
    }

    /// Whether `presented` is one of the keys; every digest is compared, byte by byte, in full.
    pub fn admit(&self, presented: &str) -> bool {
        let digest: [u8; 32] = Sha256::digest(presented.as_bytes()).into();
        let matches = self
            .digests
            .iter()
            .map(|known| known.iter().zip(&digest).fold(0u8, |acc, (x, y)| acc | (x ^ y)))
            .fold(0u32, |count, difference| count + u32::from(difference == 0));
        !presented.is_empty() && matches > 0
    }
}

/// With keys configured, a request to /v1 needs `Authorization: Bearer <key>`; health, metrics and
/// the API description stay open.
pub async fn require_api_key(State(state): State<AppState>, request: Request, next: Next) -> Response {
    if !state.keys.required() || !request.uri().path().starts_with("/v1/") {
        return next.run(request).await;
    }
    let presented = request
        .headers()
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .unwrap_or("");
    if state.keys.admit(presented) {
        return next.run(request).await;
    }
    let mut response = ApiError::new(
        StatusCode::UNAUTHORIZED,
        "Unauthorized",
        "a valid `Authorization: Bearer <key>` header is required",
    )
    .into_response();
    response.headers_mut().insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
    response
}

/// Browsers on the listed origins may call the API and read the headers that matter to it.
pub fn cors(origins: &[String]) -> CorsLayer {
    let origins: Vec<HeaderValue> = origins.iter().filter_map(|o| HeaderValue::from_str(o.trim()).ok()).collect();
    CorsLayer::new()
        .allow_origin(AllowOrigin::list(origins))
        .allow_methods([Method::GET, Method::POST, Method::DELETE])
        .allow_headers([
            header::CONTENT_TYPE,
            header::AUTHORIZATION,
            header::ACCEPT,
            HeaderName::from_static("idempotency-key"),
        ])
        .expose_headers([header::LOCATION, header::RETRY_AFTER, HeaderName::from_static("x-request-id")])
}

#[cfg(test)]
mod tests {
    use super::ApiKeys;

    fn keys(list: &[&str]) -> crate::error::Result<ApiKeys> {
        ApiKeys::new(&list.iter().map(|k| k.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn keys_compare_exactly() {
        let keys = keys(&["secret", "other-key"]).unwrap();
        assert!(keys.required());
        assert!(keys.admit("secret") && keys.admit("other-key"));
        assert!(!keys.admit("secreT") && !keys.admit("secret2") && !keys.admit("secre") && !keys.admit(""));
    }

    /// `WINDMETA_API_KEYS="k1,"` splits into "k1" and "": the empty key must not be accepted as a
    /// key, or a request without `Authorization` would match it.
    #[test]
    fn empty_blank_and_padded_keys_are_refused() {
        for list in [&["k1", ""][..], &[""], &["k1", "   "], &[" k1"], &["k\u{7f}1"]] {
            let error = keys(list).unwrap_err().to_string();
            assert!(error.starts_with("api_keys["), "{list:?}: {error}");
        }
        assert!(!keys(&[]).unwrap().required());
    }
}
