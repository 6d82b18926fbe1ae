//! Prometheus metrics: requests by matched route, method and status, their latency, and job
//! outcomes. The recorder is process-wide, installed once.

use crate::service::AppState;
use axum::extract::{MatchedPath, Request};
use axum::http::header;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use metrics_exporter_prometheus::{PrometheusBuilder, PrometheusHandle};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

/// How often recorded samples are folded into the histograms' rolling summaries. Until they are,
/// every request's latency is kept as a raw sample, so without upkeep (and with no scraper) the
/// recorder would grow by a few bytes per request for ever.
const UPKEEP_INTERVAL: Duration = Duration::from_secs(5);

fn handle() -> &'static PrometheusHandle {
    static HANDLE: OnceLock<PrometheusHandle> = OnceLock::new();
    HANDLE.get_or_init(|| {
        let handle = PrometheusBuilder::new().install_recorder().expect("the metrics recorder installs once");
        let upkeep = handle.clone();
        std::thread::Builder::new()
            .name("metrics-upkeep".into())
            .spawn(move || {
                loop {
                    std::thread::sleep(UPKEEP_INTERVAL);
                    upkeep.run_upkeep();
                }
            })
            .expect("the metrics upkeep thread starts");
        handle
    })
}

pub fn router() -> OpenApiRouter<AppState> {
    handle();
    OpenApiRouter::new().routes(routes!(prometheus_metrics))
}

/// Metrics in the Prometheus text format.
#[utoipa::path(get, path = "/metrics", tag = "health",
    responses((status = 200, description = "Prometheus text exposition", body = String, content_type = "text/plain")))]
async fn prometheus_metrics() -> impl IntoResponse {
    ([(header::CONTENT_TYPE, "text/plain; version=0.0.4")], handle().render())
}

/// Counts and times every request under its route pattern (not its raw path, which has ids).
pub async fn track(request: Request, next: Next) -> Response {
    let route = request.extensions().get::<MatchedPath>().map_or("unmatched".to_string(), |p| p.as_str().to_string());
    let method = request.method().to_string();
    let started = Instant::now();
    let response = next.run(request).await;
    let status = response.status().as_u16().to_string();
    let labels = [("route", route), ("method", method), ("status", status)];
    metrics::counter!("windmeta_http_requests_total", &labels).increment(1);
    metrics::histogram!("windmeta_http_request_seconds", &labels).record(started.elapsed().as_secs_f64());
    response
}
