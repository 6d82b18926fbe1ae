//! The job workers. Each claims work from the lease tables, runs the numerical part on a blocking
//! thread (the core parallelises with rayon there, never on the async runtime), renews its lease
//! and saves progress every second, and stores the outcome guarded by the lease. A worker that dies
//! loses its lease and the work is taken up again.
//!
//! A calibration is spread over the replicas: its worker plans it (selection experiments, scales,
//! structures), queues the other experiments as tasks in chunks, works on them itself, and
//! assembles the metamodel when every chunk is done. Idle workers of any replica take tasks before
//! new jobs. Validations and exceedance requests run whole on the worker that claimed them.

use super::analyses::AnalysisJob;
use super::exceedance::{ExceedanceJob, held_inputs};
use super::lease::LeaseKeeper;
use super::store::{Store, TaskRow};
use super::{AppState, CalibrationRequest, ValidationJob};
use crate::analysis::validate;
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress, Silent};
use crate::study::Study;
use crate::surrogate::phases::{CalibrationPlan, ExperimentFit, assemble, fit_experiments, plan};
use crate::surrogate::{CalibrationOptions, Metamodel, StageSeconds};
use serde::{Deserialize, Serialize};
use std::future::Future;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tracing::Instrument;

/// Experiments per task: large enough that a task's overhead (rebuilding the study, a lease) is
/// small against its work, small enough that a full-size calibration has tasks for every replica.
const EXPERIMENTS_PER_TASK: usize = 10;

/// What the blocking work and its async supervisor share: the work reports progress here and
/// reads whether to stop.
#[derive(Default)]
struct Supervision {
    /// Latest progress, saved at the next heartbeat.
    progress: Mutex<Option<Progress>>,
    /// Set by the supervisor on a cancel request, a shutdown or a lease in doubt; read by the work
    /// between steps.
    cancel: AtomicBool,
    /// Whether a client asked for the cancellation. Only then is the job recorded as cancelled: a
    /// shutdown or a lease in doubt gives the job back to the queue for another worker.
    requested: AtomicBool,
}

impl Observer for Supervision {
    fn progress(&self, progress: Progress) {
        *self.progress.lock().expect("progress lock") = Some(progress);
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
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

/// Who holds a lease, for people reading the tables: host and process id.
fn replica_name() -> String {
    let host = std::env::var("HOSTNAME").unwrap_or_else(|_| "host".into());
    format!("{host}-pid{}", std::process::id())
}

async fn worker(state: AppState) {
    let owner = format!("{}-{}", replica_name(), uuid::Uuid::new_v4().simple());
    while !state.draining.load(Ordering::Relaxed) {
        let claimed = match state.store.claim_task(&owner, state.config.lease_ms, None).await {
            Ok(Some(task)) => {
                let span = tracing::info_span!("task", job = %task.job_id, chunk = task.chunk);
                run_task(&state, &owner, task, None).instrument(span).await;
                continue;
            }
            Ok(None) => state.store.claim(&owner, state.config.lease_ms).await,
            Err(error) => Err(error),
        };
        match claimed {
            Ok(Some(job)) => {
                let span = tracing::info_span!("job", id = %job.id, kind = %job.kind);
                run(&state, &owner, job.id, &job.kind, job.request).instrument(span).await
            }
            Ok(None) => {
                tokio::select! {
                    _ = state.wake.notified() => {}
                    _ = tokio::time::sleep(Duration::from_millis(500)) => {}
                }
            }
            Err(error) => {
                tracing::error!(%error, "claiming work failed");
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
        }
    }
}

/// A chunk of a calibration's experiments, as queued.
#[derive(Debug, Serialize, Deserialize)]
struct TaskRequest {
    calibration: CalibrationRequest,
    plan: CalibrationPlan,
    experiments: Vec<usize>,
}

/// Runs a task with its own lease; `parent` is the coordinating job's cancel flag when the
/// coordinator runs it itself.
async fn run_task(state: &AppState, owner: &str, task: TaskRow, parent: Option<&Supervision>) {
    let store = &state.store;
    let (job_id, chunk) = (task.job_id.clone(), task.chunk);
    let supervision = Arc::new(Supervision::default());
    let observer = supervision.clone();
    let config = state.config.clone();
    let span = tracing::Span::current();
    let mut work = tokio::task::spawn_blocking(move || -> Result<Vec<ExperimentFit>> {
        let _in_task = span.enter();
        let request: TaskRequest =
            serde_json::from_str(&task.request).map_err(|e| Error::invalid("task", e.to_string()))?;
        let (study, options) = request.calibration.resolve(&config)?;
        fit_experiments(&study, &options, &request.plan, &request.experiments, 0, observer.as_ref())
    });
    let mut ticker = tokio::time::interval(Duration::from_secs(1));
    let mut lease = LeaseKeeper::claimed(state.config.lease_ms);
    let result = loop {
        tokio::select! {
            result = &mut work => break result,
            _ = ticker.tick() => {
                let mut stop = state.draining.load(Ordering::Relaxed) || parent.is_some_and(|p| p.cancelled());
                if lease.due() {
                    match store.heartbeat_task(&job_id, chunk, owner, state.config.lease_ms).await {
                        Ok(Some(true)) => lease.renewed(),
                        // The task was withdrawn (its job cancelled) or taken by another worker.
                        Ok(_) => stop = true,
                        Err(error) => {
                            tracing::warn!(%error, "renewing a task's lease failed");
                            stop |= !lease.failed();
                        }
                    }
                }
                if stop {
                    supervision.cancel.store(true, Ordering::Relaxed);
                }
            }
        }
    };
    let (finished, text) = match result {
        Ok(Ok(fits)) => (Some("done"), serde_json::to_string(&fits).expect("fits serialise")),
        Ok(Err(Error::Cancelled)) => (None, String::new()),
        Ok(Err(error)) => (Some("failed"), task_failure(&error)),
        Err(panic) => (Some("failed"), task_failure(&Error::Internal(format!("the task panicked: {panic}")))),
    };
    let recorded = match finished {
        Some(outcome) => lease
            .persist("a task's outcome", || store.finish_task(&job_id, chunk, owner, outcome, &text))
            .await
            .map(|_| ()),
        None => lease.persist("releasing a task", || store.release_task(&job_id, chunk, owner)).await,
    };
    if let Err(error) = recorded {
        tracing::error!(%error, "recording a task failed");
    }
}

/// A failed task's error as its row keeps it: JSON, so that the coordinating job fails with the
/// same kind of error (bad input, numerics, internal) wherever the task ran.
fn task_failure(error: &Error) -> String {
    serde_json::to_string(error).expect("errors serialise")
}

/// What a job produced.
enum JobOutput {
    Metamodel(Box<Metamodel>),
    /// A validation report or a sampling request's answer, as JSON.
    Answer(String),
}

type WorkFuture = Pin<Box<dyn Future<Output = Result<(JobOutput, String)>> + Send>>;

/// A blocking computation as a future, in the caller's span (its job); a panic becomes an error.
async fn blocking<T: Send + 'static>(work: impl FnOnce() -> Result<T> + Send + 'static) -> Result<T> {
    let span = tracing::Span::current();
    tokio::task::spawn_blocking(move || span.in_scope(work))
        .await
        .map_err(|panic| Error::Internal(format!("the job panicked: {panic}")))?
}

/// A stored metamodel and its study, for jobs that sample it.
async fn stored_metamodel(store: &Store, id: &str) -> Result<(Metamodel, Study)> {
    let body = store
        .metamodel_body(id)
        .await
        .map_err(|e| Error::Internal(format!("database: {e}")))?
        .ok_or_else(|| Error::invalid("metamodel_id", "the metamodel was deleted"))?;
    blocking(move || {
        let metamodel = Metamodel::from_json(&body)?;
        let study = metamodel.study()?;
        Ok((metamodel, study))
    })
    .await
}

fn parse<T: serde::de::DeserializeOwned>(request: &str) -> Result<T> {
    serde_json::from_str(request).map_err(|e| Error::invalid("request", e.to_string()))
}

/// Reads a job's request into the work that answers it.
async fn prepare(
    state: &AppState,
    id: &str,
    owner: &str,
    kind: &str,
    request: &str,
    supervision: Arc<Supervision>,
) -> Result<WorkFuture> {
    match kind {
        "calibration" => {
            let request: CalibrationRequest = parse(request)?;
            let (checked, config) = (request.clone(), state.config.clone());
            let (study, options) = blocking(move || checked.resolve(&config)).await?;
            let work =
                coordinate(state.clone(), id.to_string(), owner.to_string(), request, study, options, supervision);
            Ok(Box::pin(work))
        }
        "validation" => {
            let job: ValidationJob = parse(request)?;
            let (metamodel, study) = stored_metamodel(&state.store, &job.metamodel_id).await?;
            Ok(Box::pin(blocking(move || {
                let inputs = held_inputs(&study, &job.fixed)?;
                let report = validate(&metamodel, &study, &inputs, job.samples, job.seed, supervision.as_ref())?;
                Ok((JobOutput::Answer(serde_json::to_string(&report).expect("a report serialises")), study.name))
            })))
        }
        "exceedance" => {
            let job: ExceedanceJob = parse(request)?;
            let (metamodel, study) = stored_metamodel(&state.store, &job.metamodel_id).await?;
            Ok(Box::pin(blocking(move || {
                let answer = job.request.answer(&metamodel, &study, &job.metamodel_id, supervision.as_ref())?;
                Ok((JobOutput::Answer(serde_json::to_string(&answer).expect("a curve serialises")), study.name))
            })))
        }
        "hazard" | "fragility" | "sensitivity" => {
            let job: AnalysisJob = parse(request)?;
            let (metamodel, study) = stored_metamodel(&state.store, &job.metamodel_id).await?;
            Ok(Box::pin(blocking(move || {
                let answer = job.request.answer(&metamodel, &study, &job.metamodel_id, supervision.as_ref())?;
                Ok((JobOutput::Answer(serde_json::to_string(&answer).expect("an answer serialises")), study.name))
            })))
        }
        other => Err(Error::invalid("kind", format!("unknown job kind `{other}`"))),
    }
}

/// A database call of a running job, tried again every second through transient faults until it
/// answers or the job is cancelled: the job's heartbeat cancels it when the lease is lost.
async fn through_faults<T, F: Future<Output = std::result::Result<T, sqlx::Error>>>(
    supervision: &Supervision,
    what: &str,
    mut call: impl FnMut() -> F,
) -> Result<T> {
    loop {
        match call().await {
            Ok(value) => return Ok(value),
            Err(_) if supervision.cancelled() => return Err(Error::Cancelled),
            Err(error) => {
                tracing::warn!(%error, what, "a database call failed; trying again");
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
        }
    }
}

/// A calibration spread over the replicas (see the module's description).
async fn coordinate(
    state: AppState,
    id: String,
    owner: String,
    request: CalibrationRequest,
    study: Study,
    options: CalibrationOptions,
    supervision: Arc<Supervision>,
) -> Result<(JobOutput, String)> {
    let study = Arc::new(study);
    let options = Arc::new(options);
    let planned = {
        let (study, options, supervision) = (study.clone(), options.clone(), supervision.clone());
        Arc::new(blocking(move || plan(&study, &options, supervision.as_ref())).await?)
    };
    let started = Instant::now();
    let remaining = planned.plan.remaining();
    let tasks: Vec<String> = remaining
        .chunks(EXPERIMENTS_PER_TASK)
        .map(|experiments| {
            let task = TaskRequest {
                calibration: request.clone(),
                plan: planned.plan.clone(),
                experiments: experiments.to_vec(),
            };
            serde_json::to_string(&task).expect("a task serialises")
        })
        .collect();
    let store = &state.store;
    through_faults(&supervision, "queueing tasks", || store.insert_tasks(&id, &tasks)).await?;
    state.wake.notify_waiters();
    let mut fits = {
        let (planned, options, supervision) = (planned.clone(), options.clone(), supervision.clone());
        blocking(move || planned.fit_selection(&options, supervision.as_ref())).await?
    };
    let total = planned.plan.design.len();
    loop {
        if supervision.cancelled() {
            return Err(Error::Cancelled);
        }
        let tally = through_faults(&supervision, "counting tasks", || store.task_tally(&id)).await?;
        if let Some(failure) = tally.failure {
            return Err(serde_json::from_str(&failure).unwrap_or(Error::Internal(failure)));
        }
        let done = fits.len() + (tally.done as usize * EXPERIMENTS_PER_TASK).min(remaining.len());
        supervision.progress(Progress::Experiments { done, total });
        if tally.done == tally.total {
            break;
        }
        let claimed = through_faults(&supervision, "claiming a task", || {
            store.claim_task(&owner, state.config.lease_ms, Some(&id))
        });
        match claimed.await? {
            Some(task) => {
                let span = tracing::info_span!("task", chunk = task.chunk);
                run_task(&state, &owner, task, Some(&supervision)).instrument(span).await
            }
            None => tokio::time::sleep(Duration::from_millis(250)).await,
        }
    }
    for text in through_faults(&supervision, "reading task results", || store.task_results(&id)).await? {
        let chunk: Vec<ExperimentFit> =
            serde_json::from_str(&text).map_err(|e| Error::Internal(format!("a stored task result: {e}")))?;
        fits.extend(chunk);
    }
    let seconds = StageSeconds { coefficients: started.elapsed().as_secs_f64(), ..planned.seconds.clone() };
    let name = study.name.clone();
    let metamodel = blocking(move || assemble(&study, &options, &planned, fits, seconds, &Silent)).await?;
    Ok((JobOutput::Metamodel(Box::new(metamodel)), name))
}

async fn run(state: &AppState, owner: &str, id: String, kind: &str, request: String) {
    let store: &Store = &state.store;
    let supervision = Arc::new(Supervision::default());
    let mut lease = LeaseKeeper::claimed(state.config.lease_ms);
    let mut work = match prepare(state, &id, owner, kind, &request, supervision.clone()).await {
        Ok(work) => work,
        Err(error) => {
            let reason = error.to_string();
            let _ = lease.persist("a failure", || store.finish(&id, owner, "failed", Some(&reason), None)).await;
            return;
        }
    };
    tracing::info!("job started");
    let mut ticker = tokio::time::interval(Duration::from_secs(1));
    let result = loop {
        tokio::select! {
            result = &mut work => break result,
            _ = ticker.tick() => {
                if lease.due() {
                    let progress = supervision.progress.lock().expect("progress lock").clone();
                    let text = progress.map(|p| serde_json::to_string(&p).expect("progress serialises"));
                    match store.heartbeat(&id, owner, state.config.lease_ms, text.as_deref()).await {
                        Ok(Some(cancel)) => {
                            lease.renewed();
                            if cancel {
                                supervision.requested.store(true, Ordering::Relaxed);
                                supervision.cancel.store(true, Ordering::Relaxed);
                            }
                        }
                        Ok(None) => supervision.cancel.store(true, Ordering::Relaxed), // lease lost: stop, discard
                        Err(error) => {
                            tracing::warn!(%error, "renewing a job's lease failed");
                            if !lease.failed() {
                                supervision.cancel.store(true, Ordering::Relaxed);
                            }
                        }
                    }
                }
                if state.draining.load(Ordering::Relaxed) {
                    supervision.cancel.store(true, Ordering::Relaxed);
                }
            }
        }
    };
    let outcome = match result {
        Ok((JobOutput::Metamodel(metamodel), preset)) => {
            let metamodel_id = uuid::Uuid::new_v4().to_string();
            let body = serde_json::to_string(&metamodel).expect("a metamodel serialises");
            lease.persist("a metamodel", || store.complete(&id, owner, &metamodel_id, &preset, &body)).await.map(|_| ())
        }
        Ok((JobOutput::Answer(body), _)) => {
            lease.persist("an answer", || store.finish(&id, owner, "succeeded", None, Some(&body))).await.map(|_| ())
        }
        Err(Error::Cancelled) if supervision.requested.load(Ordering::Relaxed) => {
            lease.persist("a cancellation", || store.finish(&id, owner, "cancelled", None, None)).await.map(|_| ())
        }
        // A shutdown or a lease in doubt: the job goes back to the queue (a no-op when another
        // worker has taken it meanwhile, since the release is guarded by the owner).
        Err(Error::Cancelled) => lease.persist("releasing a job", || store.release(&id, owner)).await,
        Err(error) => {
            let reason = error.to_string();
            lease.persist("a failure", || store.finish(&id, owner, "failed", Some(&reason), None)).await.map(|_| ())
        }
    };
    if let Err(error) = outcome {
        tracing::error!(%error, "recording the outcome failed");
    }
    let state_name = match state.store.job(&id).await {
        Ok(Some(row)) => row.state,
        _ => "unknown".into(),
    };
    tracing::info!(state = %state_name, "job ended");
    metrics::counter!("windmeta_jobs_total", "kind" => kind.to_string(), "outcome" => state_name).increment(1);
}
