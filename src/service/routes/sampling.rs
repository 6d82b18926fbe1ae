//! What every sampling route shares: answer at once on a blocking thread, within the server's
//! synchronous slots and timeout and stopped when the client leaves, or queue the request as an
//! operation when it is large or the client prefers.

use super::accept_job;
use super::operations::Operation;
use super::queue::idempotency_key;
use crate::progress::Observer;
use crate::service::AppState;
use crate::service::cache::Loaded;
use crate::service::error::{ApiError, ProblemDetails};
use crate::service::rendering::Rendering;
use crate::service::watch::{RequestWatch, StopOnDrop};
use crate::service::work::Job;
use crate::study::Study;
use crate::surrogate::Metamodel;
use axum::http::{HeaderMap, header};
use axum::response::{IntoResponse, Response as HttpResponse};
use std::sync::Arc;
use std::time::Duration;

/// Seconds a client should wait before offering a synchronous request again.
const BUSY_RETRY_S: u64 = 1;

/// Whether the client asked for the answer as an operation (RFC 7240 `Prefer: respond-async`).
fn prefers_async(headers: &HeaderMap) -> bool {
    headers
        .get_all("prefer")
        .iter()
        .filter_map(|v| v.to_str().ok())
        .any(|v| v.split(',').any(|p| p.trim().eq_ignore_ascii_case("respond-async")))
}

/// The rendered answer of a synchronous request, made on a blocking thread.
pub type Work = Box<
    dyn FnOnce(&Metamodel, &Study, &dyn Observer, Rendering) -> crate::error::Result<(&'static str, String)> + Send,
>;

/// Answers with `work` at once when its metamodel `storms` are within the synchronous limit and
/// the client did not prefer otherwise; queues the job `queued` makes as an operation (202) when
/// not, and always
/// when `storms` is `None` (a request that runs reference storms too).
pub async fn answer_or_queue(
    state: &AppState,
    headers: &HeaderMap,
    loaded: Loaded,
    storms: Option<usize>,
    queued: impl FnOnce() -> Job,
    work: Work,
) -> Result<HttpResponse, ApiError> {
    // A key is only used when the request is queued, but a malformed one is refused either way.
    idempotency_key(headers)?;
    if storms.is_none_or(|storms| storms > state.config.max_sync_samples) || prefers_async(headers) {
        return accept_job(state, headers, queued()).await;
    }
    answer_now(state, headers, loaded, work).await
}

/// Answers with `work` at once on a blocking thread, within the server's synchronous slots and
/// timeout, and stopped when the client leaves.
pub async fn answer_now(
    state: &AppState,
    headers: &HeaderMap,
    loaded: Loaded,
    work: Work,
) -> Result<HttpResponse, ApiError> {
    let slots = state.config.sync_request_slots();
    let permit = state.sampling.clone().try_acquire_owned().map_err(|_| {
        ApiError::unavailable(
            format!("{slots} sampling requests are being answered; retry, or send `Prefer: respond-async`"),
            BUSY_RETRY_S,
        )
    })?;
    let accept = headers.get(header::ACCEPT).and_then(|v| v.to_str().ok()).unwrap_or("application/json");
    let rendering = Rendering::from_accept(accept);
    let watch = Arc::new(RequestWatch::new(state.draining.clone()));
    let _stop_when_the_client_leaves = StopOnDrop(watch.clone());
    let running = {
        let watch = watch.clone();
        tokio::task::spawn_blocking(move || {
            // Held until the sampling has stopped, whatever became of the request.
            let _permit = permit;
            let (metamodel, study) = (&loaded.metamodel, &loaded.study);
            work(metamodel, study, watch.as_ref(), rendering)
        })
    };
    let timeout = Duration::from_secs(state.config.sync_timeout_s);
    let (content_type, body) = match tokio::time::timeout(timeout, running).await {
        Ok(joined) => match joined.map_err(ApiError::internal)? {
            Ok(rendered) => rendered,
            Err(crate::error::Error::Cancelled) => {
                return Err(ApiError::unavailable("the server is shutting down", BUSY_RETRY_S));
            }
            Err(error) => return Err(error.into()),
        },
        Err(_) => {
            watch.stop();
            return Err(ApiError::unavailable(
                format!(
                    "not answered within {} s; ask for fewer samples or send `Prefer: respond-async`",
                    timeout.as_secs()
                ),
                BUSY_RETRY_S,
            ));
        }
    };
    Ok(([(header::CONTENT_TYPE, content_type)], body).into_response())
}

/// The answers a sampling route gives besides its 200, for the OpenAPI description (the handlers
/// build these answers through [`answer_or_queue`] and the error type, not through this type).
#[derive(utoipa::IntoResponses)]
#[expect(dead_code, reason = "a description of responses, never built")]
pub enum SamplingResponses {
    #[response(status = 202, description = "Queued as an operation; follow `Location`",
        headers(("Location" = String, description = "The operation"), ("Retry-After" = u64, description = "Seconds before polling")))]
    Queued(Operation),
    #[response(status = 404, description = "No such metamodel", content_type = "application/problem+json")]
    NotFound(ProblemDetails),
    #[response(
        status = 422,
        description = "A field is invalid (named in `errors`), or a sample diverged",
        content_type = "application/problem+json"
    )]
    Invalid(ProblemDetails),
    #[response(status = 503, description = "The queue is full (asynchronous requests), every synchronous sampling slot is taken, the request was not answered within the server's timeout, the server is shutting down, or the database does not answer now",
        content_type = "application/problem+json", headers(("Retry-After" = u64, description = "Seconds before trying again")))]
    Unavailable(ProblemDetails),
}
