//! The job workers. Each claims work from the lease tables, runs the numerical part on a blocking
//! thread (the core parallelises with rayon there, never on the async runtime), renews its lease
//! and saves progress every second, and stores the outcome guarded by the lease. A worker that dies
//! loses its lease and the work is taken up again.
//!
//! A calibration is spread over the replicas: its worker runs the selection experiments, queues
//! each mode's structure selection as a task, then the other experiments in chunks, then the
//! expansions in chunks, works on each phase's tasks itself beside the other replicas' workers,
//! and assembles the metamodel when every chunk is done. An answer queues its metamodel storms, and a
//! certified answer its reference storms, the same way ([`StormTasks`]). Idle workers of any
//! replica take tasks before new jobs. The rest of a job runs whole on the worker that claimed it.

use super::lease::LeaseKeeper;
use super::store::Store;
use super::supervision::{Supervision, blocking, through_faults};
use super::tasks::{
    EXPERIMENTS_PER_TASK, ExpansionTasks, Experiments, JobTasks, StormTasks, Structure, TaskRequest, run_task,
    work_through_tasks,
};
use super::work::Job;
use super::{AppState, CalibrationRequest};
use crate::analysis::{held_inputs, validate};
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress};
use crate::study::Study;
use crate::surrogate::assembly::assemble;
use crate::surrogate::identify::StructureChoice;
use crate::surrogate::phases::{ExperimentFit, Planned, Selection, select};
use crate::surrogate::{CalibrationOptions, Metamodel, StageSeconds};
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicI64, Ordering};
use std::time::{Duration, Instant};
use tracing::Instrument;

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

/// What a job produced.
enum JobOutput {
    Metamodel(Box<Metamodel>),
    /// A validation report or a sampling request's answer, as JSON.
    Answer(String),
}

type WorkFuture = Pin<Box<dyn Future<Output = Result<(JobOutput, String)>> + Send>>;

/// Reads a job's request into the work that answers it.
async fn prepare(
    state: &AppState,
    id: &str,
    owner: &str,
    kind: &str,
    request: &str,
    supervision: Arc<Supervision>,
) -> Result<WorkFuture> {
    match Job::stored(kind, request)? {
        Job::Calibration(request) => {
            let (checked, config) = (request.clone(), state.config.clone());
            let (study, options) = blocking(move || checked.resolve(&config)).await?;
            let work =
                coordinate(state.clone(), id.to_string(), owner.to_string(), *request, study, options, supervision);
            Ok(Box::pin(work))
        }
        Job::Validation(job) => {
            let metamodel_id = job.metamodel_id.clone();
            sampling_job(state, &metamodel_id, supervision, move |metamodel, study, observer| {
                let inputs = held_inputs(study, &job.fixed)?;
                validate(metamodel, study, &inputs, job.samples, job.seed, observer)
            })
            .await
        }
        Job::Exceedance(job) => {
            let storms = storm_tasks(state, id, owner, &job.metamodel_id);
            let metamodel_id = job.metamodel_id.clone();
            sampling_job(state, &metamodel_id, supervision, move |metamodel, study, observer| {
                job.request.answer(metamodel, study, &job.metamodel_id, &storms, observer)
            })
            .await
        }
        Job::Hazard(job) | Job::Fragility(job) | Job::Sensitivity(job) | Job::Serviceability(job) | Job::Sweep(job) => {
            let storms = storm_tasks(state, id, owner, &job.metamodel_id);
            let metamodel_id = job.metamodel_id.clone();
            sampling_job(state, &metamodel_id, supervision, move |metamodel, study, observer| {
                job.request.answer(metamodel, study, &job.metamodel_id, &storms, observer)
            })
            .await
        }
    }
}

/// A job that samples a stored metamodel: `answer` on it, off the runtime, the answer's JSON the
/// job's output.
async fn sampling_job<T: serde::Serialize>(
    state: &AppState,
    metamodel_id: &str,
    supervision: Arc<Supervision>,
    answer: impl FnOnce(&Metamodel, &Study, &Supervision) -> Result<T> + Send + 'static,
) -> Result<WorkFuture> {
    let loaded = state.metamodels.for_work(&state.store, metamodel_id, supervision.as_ref()).await?;
    Ok(Box::pin(blocking(move || {
        let (metamodel, study) = (&loaded.metamodel, &loaded.study);
        let answer = answer(metamodel, study, supervision.as_ref())?;
        Ok((JobOutput::Answer(serde_json::to_string(&answer).expect("an answer serialises")), study.name.clone()))
    })))
}

/// Where the job's answer runs its storms: as tasks of the job.
fn storm_tasks(state: &AppState, id: &str, owner: &str, metamodel_id: &str) -> StormTasks {
    StormTasks { tasks: job_tasks(state, id, owner, 0), metamodel_id: metamodel_id.to_string() }
}

/// The job's tasks, queued from chunk `next_chunk` on.
fn job_tasks(state: &AppState, id: &str, owner: &str, next_chunk: i64) -> JobTasks {
    JobTasks {
        state: state.clone(),
        job_id: id.to_string(),
        owner: owner.to_string(),
        runtime: tokio::runtime::Handle::current(),
        next_chunk: AtomicI64::new(next_chunk),
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
    let selection = {
        let (study, options, supervision) = (study.clone(), options.clone(), supervision.clone());
        blocking(move || select(&study, &options, supervision.as_ref())).await?
    };
    let planned = Arc::new(choose_structures(&state, &id, &owner, &request, selection, &supervision).await?);
    let started = Instant::now();
    let remaining = planned.plan.remaining();
    let first = planned.plan.structures.len() as i64;
    let tasks: Vec<String> = remaining
        .chunks(EXPERIMENTS_PER_TASK)
        .map(|experiments| {
            let task = TaskRequest::Experiments(Box::new(Experiments {
                calibration: request.clone(),
                plan: planned.plan.clone(),
                experiments: experiments.to_vec(),
            }));
            serde_json::to_string(&task).expect("a task serialises")
        })
        .collect();
    let store = &state.store;
    through_faults(supervision.as_ref(), "queueing tasks", || store.insert_tasks(&id, first, &tasks)).await?;
    state.wake.notify_waiters();
    let mut fits = {
        let (planned, options, supervision) = (planned.clone(), options.clone(), supervision.clone());
        blocking(move || planned.fit_selection(&options, supervision.as_ref())).await?
    };
    let (selection, total) = (fits.len(), planned.plan.design.len());
    let done = |tasks: usize| {
        let done = selection + (tasks * EXPERIMENTS_PER_TASK).min(remaining.len());
        supervision.progress(Progress::Experiments { done, total });
    };
    for text in work_through_tasks(&state, &id, &owner, supervision.as_ref(), first, tasks.len(), done).await? {
        let chunk: Vec<ExperimentFit> =
            serde_json::from_str(&text).map_err(|e| Error::Internal(format!("a stored task result: {e}")))?;
        fits.extend(chunk);
    }
    let seconds = StageSeconds { coefficients: started.elapsed().as_secs_f64(), ..planned.seconds.clone() };
    let name = study.name.clone();
    let next_chunk = first + tasks.len() as i64;
    let expansions = ExpansionTasks { tasks: job_tasks(&state, &id, &owner, next_chunk), calibration: request };
    let metamodel = blocking(move || {
        let expand = |targets: &[Vec<f64>]| expansions.fit(&planned.plan.design, targets, supervision.as_ref());
        assemble(&study, &options, &planned, fits, seconds, &expand, supervision.as_ref())
    })
    .await?;
    Ok((JobOutput::Metamodel(Box::new(metamodel)), name))
}

/// Each mode's structure as a task of the calibration's job (chunks 0 to modes − 1), the
/// selection held here for those this replica runs; then phase 1 done.
async fn choose_structures(
    state: &AppState,
    id: &str,
    owner: &str,
    request: &CalibrationRequest,
    selection: Selection,
    supervision: &Arc<Supervision>,
) -> Result<Planned> {
    let started = Instant::now();
    let modes = selection.modes();
    let tasks: Vec<String> = (0..modes)
        .map(|mode| {
            let task = TaskRequest::Structure(Box::new(Structure {
                calibration: request.clone(),
                selection: selection.plan.clone(),
                mode,
            }));
            serde_json::to_string(&task).expect("a task serialises")
        })
        .collect();
    let selection = Arc::new(selection);
    let outputs = {
        let _held = state.selections.hold(id, selection.clone());
        through_faults(supervision.as_ref(), "queueing tasks", || state.store.insert_tasks(id, 0, &tasks)).await?;
        state.wake.notify_waiters();
        let done = |tasks: usize| supervision.progress(Progress::Structure { mode: (tasks + 1).min(modes) });
        work_through_tasks(state, id, owner, supervision.as_ref(), 0, tasks.len(), done).await?
    };
    let structures = outputs
        .iter()
        .map(|text| serde_json::from_str(text).map_err(|e| Error::Internal(format!("a stored structure: {e}"))))
        .collect::<Result<Vec<StructureChoice>>>()?;
    if structures.len() != modes {
        return Err(Error::Internal(format!("{} structures came back of {modes}", structures.len())));
    }
    let selection = Arc::try_unwrap(selection).unwrap_or_else(|shared| (*shared).clone());
    Ok(selection.planned(structures, started.elapsed().as_secs_f64()))
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
                                supervision.stop();
                            }
                        }
                        Ok(None) => supervision.stop(), // lease lost: stop, discard
                        Err(error) => {
                            tracing::warn!(%error, "renewing a job's lease failed");
                            if !lease.failed() {
                                supervision.stop();
                            }
                        }
                    }
                }
                if state.draining.load(Ordering::Relaxed) {
                    supervision.stop();
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
