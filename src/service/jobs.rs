//! The job workers (calibrations, validations): each claims a job from the lease table, runs it on
//! a blocking thread (the numerical core parallelises with rayon there, never on the async
//! runtime), renews the lease and saves progress every second, and stores the metamodel (or the
//! report) with the job's completion, guarded by the lease. A worker that dies loses its lease and
//! the job is taken up again.

use super::exceedance::{ExceedanceAnswer, ExceedanceJob};
use super::store::Store;
use super::{AppState, CalibrationRequest, ValidationJob};
use crate::analysis::{ValidationReport, validate};
use crate::error::{Error, Result};
use crate::problem::Problem;
use crate::surrogate::{CalibrationOptions, Metamodel, Observer, Progress, calibrate};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// What the blocking work shares with its async supervisor.
struct Shared {
    /// Latest progress, saved at the next heartbeat.
    progress: Mutex<Option<Progress>>,
    /// Set by the supervisor on a cancel request or shutdown; read by the calibration between steps.
    cancel: AtomicBool,
}

impl Observer for Shared {
    fn progress(&self, progress: Progress) {
        *self.progress.lock().expect("progress lock") = Some(progress);
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// Who holds a lease, for people reading the jobs table: host and process id.
fn replica_name() -> String {
    let host = std::env::var("HOSTNAME").unwrap_or_else(|_| "host".into());
    format!("{host}-pid{}", std::process::id())
}

/// Runs `count` workers until shutdown.
pub fn spawn_workers(state: AppState, count: usize) -> Vec<tokio::task::JoinHandle<()>> {
    (0..count)
        .map(|_| {
            let state = state.clone();
            tokio::spawn(async move { worker(state).await })
        })
        .collect()
}

async fn worker(state: AppState) {
    let owner = format!("{}-{}", replica_name(), uuid::Uuid::new_v4().simple());
    while !state.draining.load(Ordering::Relaxed) {
        match state.store.claim(&owner, state.config.lease_ms).await {
            Ok(Some(job)) => run(&state, &owner, job.id, &job.kind, job.request).await,
            Ok(None) => {
                tokio::select! {
                    _ = state.wake.notified() => {}
                    _ = tokio::time::sleep(Duration::from_millis(500)) => {}
                }
            }
            Err(error) => {
                tracing::error!(%error, "claiming a job failed");
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
        }
    }
}

/// What a job computes, ready to run on a blocking thread.
enum Work {
    Calibration(Box<Problem>, CalibrationOptions),
    Validation(Box<(Metamodel, Problem)>, usize, u64),
    Exceedance(Box<(Metamodel, Problem)>, Box<ExceedanceJob>),
}

/// What it produced.
enum Output {
    Metamodel(Box<Metamodel>),
    Report(Box<ValidationReport>),
    Curve(Box<ExceedanceAnswer>),
}

/// A stored metamodel and its study, for jobs that sample it.
async fn stored_metamodel(store: &Store, id: &str) -> Result<(Metamodel, Problem)> {
    let body = store
        .metamodel_body(id)
        .await
        .map_err(|e| Error::Numerical(format!("database: {e}")))?
        .ok_or_else(|| Error::invalid("metamodel_id", "the metamodel was deleted"))?;
    let metamodel = Metamodel::from_json(&body)?;
    let problem = metamodel.problem()?;
    Ok((metamodel, problem))
}

/// Reads a job's request into its work; the metamodel of a validation comes from the store.
async fn prepare(store: &Store, kind: &str, request: &str, config: &super::ServeArgs) -> Result<Work> {
    match kind {
        "calibration" => {
            let request: CalibrationRequest =
                serde_json::from_str(request).map_err(|e| Error::invalid("request", e.to_string()))?;
            let (problem, options) = request.resolve(config)?;
            Ok(Work::Calibration(Box::new(problem), options))
        }
        "validation" => {
            let request: ValidationJob =
                serde_json::from_str(request).map_err(|e| Error::invalid("request", e.to_string()))?;
            let loaded = stored_metamodel(store, &request.metamodel_id).await?;
            Ok(Work::Validation(Box::new(loaded), request.samples, request.seed))
        }
        "exceedance" => {
            let job: ExceedanceJob =
                serde_json::from_str(request).map_err(|e| Error::invalid("request", e.to_string()))?;
            let loaded = stored_metamodel(store, &job.metamodel_id).await?;
            Ok(Work::Exceedance(Box::new(loaded), Box::new(job)))
        }
        other => Err(Error::invalid("kind", format!("unknown job kind `{other}`"))),
    }
}

async fn run(state: &AppState, owner: &str, id: String, kind: &str, request: String) {
    let store: &Store = &state.store;
    let work = match prepare(store, kind, &request, &state.config).await {
        Ok(work) => work,
        Err(error) => {
            let _ = store.finish(&id, owner, "failed", Some(&error.to_string()), None).await;
            return;
        }
    };
    tracing::info!(job = %id, kind, "job started");
    let shared = Arc::new(Shared { progress: Mutex::new(None), cancel: AtomicBool::new(false) });
    let observer = shared.clone();
    let mut task = tokio::task::spawn_blocking(move || match work {
        Work::Calibration(problem, options) => {
            let name = problem.name.clone();
            calibrate(&problem, &options, observer.as_ref()).map(|m| (Output::Metamodel(Box::new(m)), name))
        }
        Work::Validation(loaded, samples, seed) => {
            let (metamodel, problem) = *loaded;
            validate(&metamodel, &problem, samples, seed, observer.as_ref())
                .map(|r| (Output::Report(Box::new(r)), problem.name))
        }
        Work::Exceedance(loaded, job) => {
            let (metamodel, problem) = *loaded;
            job.request
                .answer(&metamodel, &problem, &job.metamodel_id, observer.as_ref())
                .map(|a| (Output::Curve(Box::new(a)), problem.name))
        }
    });
    let mut ticker = tokio::time::interval(Duration::from_secs(1));
    let result = loop {
        tokio::select! {
            result = &mut task => break result,
            _ = ticker.tick() => {
                let progress = shared.progress.lock().expect("progress lock").clone();
                let text = progress.map(|p| serde_json::to_string(&p).expect("progress serialises"));
                match store.heartbeat(&id, owner, state.config.lease_ms, text.as_deref()).await {
                    Ok(Some(cancel)) => if cancel { shared.cancel.store(true, Ordering::Relaxed) },
                    Ok(None) => shared.cancel.store(true, Ordering::Relaxed), // lease lost: stop, discard
                    Err(error) => tracing::warn!(%error, "heartbeat failed"),
                }
                if state.draining.load(Ordering::Relaxed) {
                    shared.cancel.store(true, Ordering::Relaxed);
                }
            }
        }
    };
    let outcome = match result {
        Ok(Ok((Output::Metamodel(metamodel), preset))) => {
            let metamodel_id = uuid::Uuid::new_v4().to_string();
            let body = serde_json::to_string(&metamodel).expect("a metamodel serialises");
            store.complete(&id, owner, &metamodel_id, &preset, &body).await.map(|_| ())
        }
        Ok(Ok((Output::Report(report), _))) => {
            let body = serde_json::to_string(&report).expect("a report serialises");
            store.finish(&id, owner, "succeeded", None, Some(&body)).await.map(|_| ())
        }
        Ok(Ok((Output::Curve(curve), _))) => {
            let body = serde_json::to_string(&curve).expect("a curve serialises");
            store.finish(&id, owner, "succeeded", None, Some(&body)).await.map(|_| ())
        }
        Ok(Err(Error::Cancelled)) if state.draining.load(Ordering::Relaxed) => store.release(&id, owner).await,
        Ok(Err(Error::Cancelled)) => store.finish(&id, owner, "cancelled", None, None).await.map(|_| ()),
        Ok(Err(error)) => store.finish(&id, owner, "failed", Some(&error.to_string()), None).await.map(|_| ()),
        Err(panic) => {
            store.finish(&id, owner, "failed", Some(&format!("the job panicked: {panic}")), None).await.map(|_| ())
        }
    };
    if let Err(error) = outcome {
        tracing::error!(%error, job = %id, "recording the outcome failed");
    }
    let state_name = match state.store.job(&id).await {
        Ok(Some(row)) => row.state,
        _ => "unknown".into(),
    };
    metrics::counter!("windmeta_jobs_total", "kind" => kind.to_string(), "outcome" => state_name).increment(1);
    tracing::info!(job = %id, "job ended");
}
