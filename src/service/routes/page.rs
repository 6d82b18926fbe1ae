//! The browser page at `/`: one HTML file, its script and its style sheet, embedded in the binary
//! (no CDN, nothing fetched at run time, no JavaScript build). The page is a client of the public
//! API like any other; serving it needs no key (it holds no data), the API it calls does.
//!
//! The script is a set of ES modules (no build step) entered through `app.js`, the only one the
//! page names; each module imports the others it needs.
//!
//! Caching: the page itself is revalidated on every load (`no-cache` with an ETag, so a new binary
//! is picked up at once); it names its assets with their content digest (`/assets/app.js?v=…`),
//! and every module names the modules it imports the same way, so they are cached for a year and a
//! new version is a new address. The Content-Security-Policy
//! admits only the page's own origin: no inline script or style, no other host.

use axum::Router;
use axum::extract::{Path, Query};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::sync::LazyLock;

use crate::service::AppState;
use crate::service::error::ApiError;

/// What the page may load and whom it may talk to: itself only. `data:` images are the SVG
/// downloads' previews; `blob:` the download links the page makes of its own answers.
const CONTENT_SECURITY_POLICY: &str = "default-src 'self'; script-src 'self'; style-src 'self'; \
     img-src 'self' data: blob:; connect-src 'self'; object-src 'none'; base-uri 'none'; \
     form-action 'self'; frame-ancestors 'none'";

/// One embedded file with its type and digest.
struct Asset {
    name: &'static str,
    body: String,
    content_type: &'static str,
    /// The first 16 hex digits of the body's SHA-256: the ETag and the version in its address.
    digest: String,
}

impl Asset {
    fn new(name: &'static str, body: String, content_type: &'static str) -> Asset {
        let digest = Sha256::digest(body.as_bytes()).iter().take(8).map(|b| format!("{b:02x}")).collect();
        Asset { name, body, content_type, digest }
    }
}

const SCRIPT: &str = "text/javascript; charset=utf-8";

/// The page's modules, each after the modules it imports, and its style sheet.
const SOURCES: [(&str, &str, &str); 8] = [
    ("charts.js", include_str!("../page/charts.js"), SCRIPT),
    ("client.js", include_str!("../page/client.js"), SCRIPT),
    ("operations.js", include_str!("../page/operations.js"), SCRIPT),
    ("analyses.js", include_str!("../page/analyses.js"), SCRIPT),
    ("design.js", include_str!("../page/design.js"), SCRIPT),
    ("metamodels.js", include_str!("../page/metamodels.js"), SCRIPT),
    ("app.js", include_str!("../page/app.js"), SCRIPT),
    ("style.css", include_str!("../page/style.css"), "text/css; charset=utf-8"),
];

/// The assets as served: a module names each module it imports by its versioned address, so that a
/// changed module changes the address (and the digest) of every module that imports it.
static ASSETS: LazyLock<Vec<Asset>> = LazyLock::new(|| {
    let mut assets: Vec<Asset> = Vec::with_capacity(SOURCES.len());
    for (name, body, content_type) in SOURCES {
        let body = assets.iter().fold(body.to_string(), |body, imported| {
            body.replace(&format!("'./{}'", imported.name), &format!("'./{}?v={}'", imported.name, imported.digest))
        });
        assets.push(Asset::new(name, body, content_type));
    }
    assets
});

/// The page with its assets' addresses carrying their digests.
static INDEX: LazyLock<Asset> = LazyLock::new(|| {
    let html = ASSETS.iter().fold(include_str!("../page/index.html").to_string(), |html, asset| {
        let address = format!("/assets/{}", asset.name);
        html.replace(&format!("\"{address}\""), &format!("\"{address}?v={}\"", asset.digest))
    });
    Asset::new("index.html", html, "text/html; charset=utf-8")
});

pub fn router() -> Router<AppState> {
    Router::new().route("/", axum::routing::get(index)).route("/assets/{name}", axum::routing::get(asset))
}

async fn index(headers: HeaderMap) -> Response {
    serve(&INDEX, &headers, "no-cache")
}

async fn asset(Path(name): Path<String>, Query(query): Query<HashMap<String, String>>, headers: HeaderMap) -> Response {
    let Some(asset) = ASSETS.iter().find(|asset| asset.name == name) else {
        return ApiError::new(StatusCode::NOT_FOUND, "Not found", format!("no asset `{name}`")).into_response();
    };
    // Only the current version's address may be kept for a year.
    let cache = if query.get("v") == Some(&asset.digest) { "public, max-age=31536000, immutable" } else { "no-cache" };
    serve(asset, &headers, cache)
}

fn serve(asset: &Asset, request: &HeaderMap, cache: &'static str) -> Response {
    let etag = format!("\"{}\"", asset.digest);
    let fresh = request
        .get(header::IF_NONE_MATCH)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|tags| tags.split(',').any(|tag| tag.trim().trim_start_matches("W/") == etag));
    let mut response =
        if fresh { StatusCode::NOT_MODIFIED.into_response() } else { asset.body.clone().into_response() };
    let headers = response.headers_mut();
    if !fresh {
        headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(asset.content_type));
    }
    headers.insert(header::ETAG, HeaderValue::from_str(&etag).expect("hex digits make a header value"));
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static(cache));
    headers.insert(header::CONTENT_SECURITY_POLICY, HeaderValue::from_static(CONTENT_SECURITY_POLICY));
    headers.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    headers.insert(header::REFERRER_POLICY, HeaderValue::from_static("no-referrer"));
    response
}
