//! Tasks: pieces of a running job that any replica's idle worker may take, each under its own
//! lease — a calibration's experiments and a certified answer's reference storms, in chunks. The
//! job that queued them works on them too while it waits for the others ([`work_through_tasks`]).
//! A task whose worker died is taken up by another; a job taken up again after its worker died
//! queues the same chunks (its plan is deterministic) and finds those done before still done.

use super::AppState;
use super::CalibrationRequest;
use super::lease::LeaseKeeper;
use super::store::TaskRow;
use super::supervision::{Supervision, blocking, through_faults};
use crate::analysis::{PairedPeak, PairedRuns, ReferenceRunner, Response};
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress};
use crate::simd::LANES;
use crate::study::Order;
use crate::surrogate::phases::{CalibrationPlan, fit_experiments};
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::atomic::{AtomicI64, Ordering};
use std::time::Duration;
use tracing::Instrument;

/// Experiments per task: one batch of the reference's vector lanes (a task of ten ran eight in
/// lanes and two in a batch of their own at the cost of eight), large enough that a task's
/// overhead (rebuilding the study, a lease) is small against its work, small enough that a
/// full-size calibration has tasks for every replica.
pub(super) const EXPERIMENTS_PER_TASK: usize = LANES;

/// Reference storms per task: a storm through both models costs about one calibration
/// experiment (a reference integration), so as many as a chunk of experiments.
const REFERENCE_STORMS_PER_TASK: usize = LANES;

/// A task as queued.
#[derive(Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub(super) enum TaskRequest {
    Experiments(Box<Experiments>),
    ReferenceStorms(ReferenceStorms),
}

/// Some of a calibration's experiments, by their place in its plan's design.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct Experiments {
    pub calibration: CalibrationRequest,
    pub plan: CalibrationPlan,
    pub experiments: Vec<usize>,
}

/// Some of a certified answer's reference storms: through both a stored metamodel and the
/// reference model, row i's wind from stream `storms[i]` of `seed`, the peaks of `response`.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct ReferenceStorms {
    metamodel_id: String,
    seed: u64,
    response: Response,
    order: Order,
    rows: Vec<Vec<f64>>,
    storms: Vec<usize>,
}

/// A paired peak as a task's output keeps it, (reference, metamodel): JSON has no infinity, so the
/// peak of a run that diverged is null.
#[derive(Debug, Serialize, Deserialize)]
struct StoredPair(Option<f64>, Option<f64>);

impl StoredPair {
    fn of(pair: &PairedPeak) -> Self {
        StoredPair(
            pair.reference.is_finite().then_some(pair.reference),
            pair.metamodel.is_finite().then_some(pair.metamodel),
        )
    }

    fn peak(&self) -> PairedPeak {
        PairedPeak { reference: self.0.unwrap_or(f64::INFINITY), metamodel: self.1.unwrap_or(f64::INFINITY) }
    }
}

/// The task's work, off the runtime: its output as JSON.
async fn work(state: &AppState, request: &str, observer: Arc<Supervision>) -> Result<String> {
    let request = request.to_string();
    let request: TaskRequest =
        blocking(move || serde_json::from_str(&request).map_err(|e| Error::invalid("task", e.to_string()))).await?;
    match request {
        TaskRequest::Experiments(task) => {
            let Experiments { calibration, plan, experiments } = *task;
            let config = state.config.clone();
            blocking(move || {
                let (study, options) = calibration.resolve(&config)?;
                let fits = fit_experiments(&study, &options, &plan, &experiments, 0, observer.as_ref())?;
                Ok(serde_json::to_string(&fits).expect("fits serialise"))
            })
            .await
        }
        TaskRequest::ReferenceStorms(task) => {
            let loaded = state.metamodels.for_work(&state.store, &task.metamodel_id, observer.as_ref()).await?;
            blocking(move || {
                let (metamodel, study) = (&loaded.metamodel, &loaded.study);
                let ReferenceStorms { seed, response, order, rows, storms, .. } = task;
                let runs = PairedRuns { metamodel, study, seed, response, order };
                let pairs = runs.run(&rows, &storms, observer.as_ref())?;
                let stored: Vec<StoredPair> = pairs.iter().map(StoredPair::of).collect();
                Ok(serde_json::to_string(&stored).expect("pairs serialise"))
            })
            .await
        }
    }
}

/// Runs a task with its own lease; `parent` is the job that queued it, when its own worker runs
/// it (the task stops when the job is cancelled).
pub(super) async fn run_task(state: &AppState, owner: &str, task: TaskRow, parent: Option<&dyn Observer>) {
    let store = &state.store;
    let (job_id, chunk) = (task.job_id.clone(), task.chunk);
    let supervision = Arc::new(Supervision::default());
    let mut work = Box::pin(work(state, &task.request, supervision.clone()));
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
                    supervision.stop();
                }
            }
        }
    };
    let finished = match result {
        Ok(output) => Some(("done", output)),
        Err(Error::Cancelled) => None,
        Err(error) => Some(("failed", task_failure(&error))),
    };
    let recorded = match finished {
        Some((outcome, text)) => lease
            .persist("a task's outcome", || store.finish_task(&job_id, chunk, owner, outcome, &text))
            .await
            .map(|_| ()),
        None => lease.persist("releasing a task", || store.release_task(&job_id, chunk, owner)).await,
    };
    if let Err(error) = recorded {
        tracing::error!(%error, "recording a task failed");
    }
}

/// A failed task's error as its row keeps it: JSON, so that the job that queued it fails with the
/// same kind of error (bad input, numerics, internal) wherever the task ran.
fn task_failure(error: &Error) -> String {
    serde_json::to_string(error).expect("errors serialise")
}

/// Works on the job's tasks from chunk `first` on until every one is done, claiming them itself
/// while idle workers of every replica claim them too, and tells `done` how many of them are done
/// as they finish; then their outputs, by chunk.
pub(super) async fn work_through_tasks(
    state: &AppState,
    job_id: &str,
    owner: &str,
    supervision: &dyn Observer,
    first: i64,
    done: impl Fn(usize),
) -> Result<Vec<String>> {
    let store = &state.store;
    loop {
        if supervision.cancelled() {
            return Err(Error::Cancelled);
        }
        let tally = through_faults(supervision, "counting tasks", || store.task_tally(job_id)).await?;
        if let Some(failure) = tally.failure {
            return Err(serde_json::from_str(&failure).unwrap_or(Error::Internal(failure)));
        }
        // The chunks before `first` are done: the job waited for them before queueing these.
        done((tally.done - first).max(0) as usize);
        if tally.done == tally.total {
            break;
        }
        let claimed = through_faults(supervision, "claiming a task", || {
            store.claim_task(owner, state.config.lease_ms, Some(job_id))
        });
        match claimed.await? {
            Some(task) => {
                let span = tracing::info_span!("task", chunk = task.chunk);
                run_task(state, owner, task, Some(supervision)).instrument(span).await
            }
            None => tokio::time::sleep(Duration::from_millis(250)).await,
        }
    }
    through_faults(supervision, "reading task results", || store.task_results(job_id, first)).await
}

/// A certified answer's reference storms as tasks of its job, for every replica's workers. The
/// answer asks for them from its blocking thread, which waits on the runtime while the job's own
/// worker works through them with the others.
pub(super) struct ReferenceTasks {
    pub state: AppState,
    pub job_id: String,
    pub owner: String,
    /// The stored metamodel the answer samples (the one in the runs it is handed).
    pub metamodel_id: String,
    pub runtime: tokio::runtime::Handle,
    /// The first chunk of the next batch (a certified annual curve asks twice: its pilot, then
    /// the rest).
    pub next_chunk: AtomicI64,
}

impl ReferenceRunner for ReferenceTasks {
    fn pairs(
        &self,
        runs: &PairedRuns,
        rows: &[Vec<f64>],
        storms: &[usize],
        observer: &dyn Observer,
    ) -> Result<Vec<PairedPeak>> {
        let requests: Vec<String> = rows
            .chunks(REFERENCE_STORMS_PER_TASK)
            .zip(storms.chunks(REFERENCE_STORMS_PER_TASK))
            .map(|(rows, storms)| {
                let task = TaskRequest::ReferenceStorms(ReferenceStorms {
                    metamodel_id: self.metamodel_id.clone(),
                    seed: runs.seed,
                    response: runs.response,
                    order: runs.order,
                    rows: rows.to_vec(),
                    storms: storms.to_vec(),
                });
                serde_json::to_string(&task).expect("a task serialises")
            })
            .collect();
        let first = self.next_chunk.fetch_add(requests.len() as i64, Ordering::Relaxed);
        let (state, job_id, total) = (&self.state, self.job_id.as_str(), rows.len());
        let outputs = self.runtime.block_on(async {
            through_faults(observer, "queueing reference storms", || {
                state.store.insert_tasks(job_id, first, &requests)
            })
            .await?;
            state.wake.notify_waiters();
            let done = |tasks: usize| {
                observer
                    .progress(Progress::ReferenceStorms { done: (tasks * REFERENCE_STORMS_PER_TASK).min(total), total })
            };
            work_through_tasks(state, job_id, &self.owner, observer, first, done).await
        })?;
        let mut pairs = Vec::with_capacity(total);
        for output in outputs {
            let stored: Vec<StoredPair> = serde_json::from_str(&output)
                .map_err(|e| Error::Internal(format!("a stored reference task's output: {e}")))?;
            pairs.extend(stored.iter().map(StoredPair::peak));
        }
        if pairs.len() != total {
            return Err(Error::Internal(format!("{} reference storms came back of {total}", pairs.len())));
        }
        Ok(pairs)
    }
}
