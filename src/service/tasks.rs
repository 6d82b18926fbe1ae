//! Tasks: pieces of a running job that any replica's idle worker may take, each under its own
//! lease — a calibration's structure selections (one per mode), experiments and expansions, an
//! answer's metamodel storms and a certified answer's reference storms, in chunks. The
//! job that queued them works on them too while it waits for the others ([`work_through_tasks`]).
//! A task whose worker died is taken up by another; a job taken up again after its worker died
//! queues the same chunks (its plan is deterministic) and finds those done before still done.

use super::AppState;
use super::CalibrationRequest;
use super::lease::LeaseKeeper;
use super::store::TaskRow;
use super::supervision::{Supervision, blocking, through_faults};
use crate::analysis::{
    Draws, OnDivergence, OnThisMachine, PairedPeak, PairedRuns, Response, StormRunner, floor_peak_sets_at,
};
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress};
use crate::simd::LANES;
use crate::study::Order;
use crate::surrogate::Metamodel;
use crate::surrogate::assembly::fit_expansions;
use crate::surrogate::pce::SparsePce;
use crate::surrogate::phases::{CalibrationPlan, Selection, fit_experiments};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex};
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

/// Metamodel storms per task: about a second of one core at full size (a free run with its wind
/// takes about a millisecond), so that a 10 000-storm answer has tasks for every replica while a
/// task's overhead (its lease, its rows and peaks as JSON) stays small against its work. An answer
/// of no more storms runs them itself.
const METAMODEL_STORMS_PER_TASK: usize = 128 * LANES;

/// A task as queued (told apart by their fields: each has one the others lack).
#[derive(Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub(super) enum TaskRequest {
    Structure(Box<Structure>),
    Experiments(Box<Experiments>),
    Expansions(Box<Expansions>),
    ReferenceStorms(ReferenceStorms),
    MetamodelStorms(MetamodelStorms),
}

/// One mode's structure selection, on the selection experiments of a plan that has no structures
/// yet: they are run again, except on the replica that coordinates the calibration, which holds
/// them ([`HeldSelections`]).
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct Structure {
    pub calibration: CalibrationRequest,
    pub selection: CalibrationPlan,
    pub mode: usize,
}

/// Some of a calibration's expansions: one per series of targets, over its plan's design.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct Expansions {
    pub calibration: CalibrationRequest,
    pub design: Vec<Vec<f64>>,
    pub targets: Vec<Vec<f64>>,
}

/// The selection experiments of the calibrations this replica coordinates, by job: a structure
/// task of such a job that this replica's worker takes reads them here rather than running them
/// again (about 200 MB at full size, held only while the structures are chosen).
#[derive(Default)]
pub(super) struct HeldSelections(Mutex<HashMap<String, Arc<Selection>>>);

/// A selection held for a job until this is dropped.
pub(super) struct HeldSelection<'a> {
    held: &'a HeldSelections,
    job_id: String,
}

impl HeldSelections {
    /// Holds `selection` for `job_id`'s tasks until the returned guard is dropped.
    pub fn hold(&self, job_id: &str, selection: Arc<Selection>) -> HeldSelection<'_> {
        self.0.lock().expect("selections lock").insert(job_id.to_string(), selection);
        HeldSelection { held: self, job_id: job_id.to_string() }
    }

    fn get(&self, job_id: &str) -> Option<Arc<Selection>> {
        self.0.lock().expect("selections lock").get(job_id).cloned()
    }
}

impl Drop for HeldSelection<'_> {
    fn drop(&mut self) {
        self.held.0.lock().expect("selections lock").remove(&self.job_id);
    }
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

/// Some of an answer's metamodel storms: row i's wind from stream `storms[i]` of `seed`, the peaks
/// of every one of `responses` (floor responses); `first` is the number of the first row among
/// the answer's, by which a failure names a storm.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct MetamodelStorms {
    metamodel_id: String,
    seed: u64,
    responses: Vec<Response>,
    on_divergence: OnDivergence,
    rows: Vec<Vec<f64>>,
    storms: Vec<usize>,
    first: usize,
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

/// The task's work for job `job_id`, off the runtime: its output as JSON.
async fn work(state: &AppState, job_id: &str, request: &str, observer: Arc<Supervision>) -> Result<String> {
    let request = request.to_string();
    let request: TaskRequest =
        blocking(move || serde_json::from_str(&request).map_err(|e| Error::invalid("task", e.to_string()))).await?;
    match request {
        TaskRequest::Structure(task) => {
            let Structure { calibration, selection, mode } = *task;
            let (config, held) = (state.config.clone(), state.selections.get(job_id));
            blocking(move || {
                let (study, options) = calibration.resolve(&config)?;
                let selection = match held {
                    Some(held) => held,
                    None => Arc::new(Selection::rerun(&study, &options, &selection, observer.as_ref())?),
                };
                let structure = selection.structure(mode, &options, observer.as_ref())?;
                Ok(serde_json::to_string(&structure).expect("a structure serialises"))
            })
            .await
        }
        TaskRequest::Expansions(task) => {
            let Expansions { calibration, design, targets } = *task;
            let config = state.config.clone();
            blocking(move || {
                let (study, options) = calibration.resolve(&config)?;
                let expansions = fit_expansions(&study, &options, &design, &targets, observer.as_ref())?;
                Ok(serde_json::to_string(&expansions).expect("expansions serialise"))
            })
            .await
        }
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
        TaskRequest::MetamodelStorms(task) => {
            let loaded = state.metamodels.for_work(&state.store, &task.metamodel_id, observer.as_ref()).await?;
            blocking(move || {
                let (metamodel, study) = (&loaded.metamodel, &loaded.study);
                let MetamodelStorms { seed, responses, on_divergence, rows, storms, first, .. } = task;
                let draws = Draws { study, rows: &rows, storms: &storms, seed, on_divergence };
                let peaks = floor_peak_sets_at(metamodel, &draws, &responses, first, observer.as_ref())?;
                Ok(serde_json::to_string(&stored_peaks(&peaks)).expect("peaks serialise"))
            })
            .await
        }
    }
}

/// Peaks as a task's output keeps them: JSON has no infinity, so a diverged storm's are null.
fn stored_peaks(peaks: &[Vec<f64>]) -> Vec<Vec<Option<f64>>> {
    peaks.iter().map(|row| row.iter().map(|p| p.is_finite().then_some(*p)).collect()).collect()
}

/// Runs a task with its own lease; `parent` is the job that queued it, when its own worker runs
/// it (the task stops when the job is cancelled).
pub(super) async fn run_task(state: &AppState, owner: &str, task: TaskRow, parent: Option<&dyn Observer>) {
    let store = &state.store;
    let (job_id, chunk) = (task.job_id.clone(), task.chunk);
    let supervision = Arc::new(Supervision::default());
    let mut work = Box::pin(work(state, &job_id, &task.request, supervision.clone()));
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
    // A job of this replica waiting for its tasks counts them again (another replica's job hears
    // of it through the store's announcement).
    state.wake.notify_waiters();
}

/// A failed task's error as its row keeps it: JSON, so that the job that queued it fails with the
/// same kind of error (bad input, numerics, internal) wherever the task ran.
fn task_failure(error: &Error) -> String {
    serde_json::to_string(error).expect("errors serialise")
}

/// Works on the job's `count` tasks from chunk `first` on until every one is done, claiming them
/// itself while idle workers of every replica claim them too, and tells `done` how many of them
/// are done as they finish; then their outputs, by chunk.
pub(super) async fn work_through_tasks(
    state: &AppState,
    job_id: &str,
    owner: &str,
    supervision: &dyn Observer,
    first: i64,
    count: usize,
    done: impl Fn(usize),
) -> Result<Vec<String>> {
    let store = &state.store;
    let chunks = first..first + count as i64;
    loop {
        if supervision.cancelled() {
            return Err(Error::Cancelled);
        }
        // Listening before counting: a task finished between the count and the wait still wakes it.
        let woken = state.wake.notified();
        tokio::pin!(woken);
        woken.as_mut().enable();
        let tally = through_faults(supervision, "counting tasks", || store.task_tally(job_id, chunks.clone())).await?;
        if let Some(failure) = tally.failure {
            return Err(serde_json::from_str(&failure).unwrap_or(Error::Internal(failure)));
        }
        done(tally.done as usize);
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
            // Another replica runs the rest: woken when a task finishes here or is announced
            // finished by another replica, polled as a fallback.
            None => {
                tokio::select! {
                    _ = woken => {}
                    _ = tokio::time::sleep(Duration::from_millis(250)) => {}
                }
            }
        }
    }
    through_faults(supervision, "reading task results", || store.task_results(job_id, chunks.clone())).await
}

/// A job's own tasks, queued from the job's blocking thread, which waits on the runtime while the
/// job's worker works through them with the other replicas' workers.
pub(super) struct JobTasks {
    pub state: AppState,
    pub job_id: String,
    pub owner: String,
    pub runtime: tokio::runtime::Handle,
    /// The chunk number of the next task queued (a job may queue several batches: an annual curve
    /// its pilot storms, then the rest; a sweep one per value).
    pub next_chunk: AtomicI64,
}

impl JobTasks {
    /// Queues `requests` as the job's next chunks and works through them; `done` is told how many
    /// of them are done as they finish. Their outputs, in the order of the requests.
    fn run(&self, requests: &[String], observer: &dyn Observer, done: impl Fn(usize)) -> Result<Vec<String>> {
        let first = self.next_chunk.fetch_add(requests.len() as i64, Ordering::Relaxed);
        let (state, job_id) = (&self.state, self.job_id.as_str());
        let outputs = self.runtime.block_on(async {
            through_faults(observer, "queueing tasks", || state.store.insert_tasks(job_id, first, requests)).await?;
            state.wake.notify_waiters();
            work_through_tasks(state, job_id, &self.owner, observer, first, requests.len(), done).await
        })?;
        if outputs.len() != requests.len() {
            return Err(Error::Internal(format!("{} tasks came back of {}", outputs.len(), requests.len())));
        }
        Ok(outputs)
    }
}

/// Expansions per task: a full-size calibration fits about thirty (a quarter of a second of one
/// core each), so that each replica gets several.
const EXPANSIONS_PER_TASK: usize = 4;

/// A calibration's expansions as tasks of its job.
pub(super) struct ExpansionTasks {
    pub tasks: JobTasks,
    pub calibration: CalibrationRequest,
}

impl ExpansionTasks {
    /// The expansion of each of `targets` over `design`, as [`fit_expansions`] fits them.
    pub fn fit(&self, design: &[Vec<f64>], targets: &[Vec<f64>], observer: &dyn Observer) -> Result<Vec<SparsePce>> {
        let requests: Vec<String> = targets
            .chunks(EXPANSIONS_PER_TASK)
            .map(|targets| {
                let task = TaskRequest::Expansions(Box::new(Expansions {
                    calibration: self.calibration.clone(),
                    design: design.to_vec(),
                    targets: targets.to_vec(),
                }));
                serde_json::to_string(&task).expect("a task serialises")
            })
            .collect();
        let mut expansions = Vec::with_capacity(targets.len());
        for output in self.tasks.run(&requests, observer, |_| {})? {
            expansions.extend(read_output::<Vec<SparsePce>>(&output)?);
        }
        if expansions.len() != targets.len() {
            return Err(Error::Internal(format!("{} expansions came back of {}", expansions.len(), targets.len())));
        }
        Ok(expansions)
    }
}

/// An answer's storms as tasks of its job, for every replica's workers: its metamodel storms in
/// chunks of [`METAMODEL_STORMS_PER_TASK`] (an answer of no more runs them itself), a certified
/// answer's reference storms in chunks of [`REFERENCE_STORMS_PER_TASK`].
pub(super) struct StormTasks {
    pub tasks: JobTasks,
    /// The stored metamodel the answer samples (the one in the runs it is handed).
    pub metamodel_id: String,
}

/// A stored task's output read back.
fn read_output<T: serde::de::DeserializeOwned>(output: &str) -> Result<T> {
    serde_json::from_str(output).map_err(|e| Error::Internal(format!("a stored task's output: {e}")))
}

impl StormRunner for StormTasks {
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
        let total = rows.len();
        let done = |tasks: usize| {
            observer.progress(Progress::ReferenceStorms { done: (tasks * REFERENCE_STORMS_PER_TASK).min(total), total })
        };
        let mut pairs = Vec::with_capacity(total);
        for output in self.tasks.run(&requests, observer, done)? {
            let stored: Vec<StoredPair> = read_output(&output)?;
            pairs.extend(stored.iter().map(StoredPair::peak));
        }
        if pairs.len() != total {
            return Err(Error::Internal(format!("{} reference storms came back of {total}", pairs.len())));
        }
        Ok(pairs)
    }

    fn floor_peak_sets(
        &self,
        metamodel: &Metamodel,
        draws: &Draws,
        responses: &[Response],
        observer: &dyn Observer,
    ) -> Result<Vec<Vec<f64>>> {
        let total = draws.rows.len();
        if total <= METAMODEL_STORMS_PER_TASK {
            return OnThisMachine.floor_peak_sets(metamodel, draws, responses, observer);
        }
        let requests: Vec<String> = draws
            .rows
            .chunks(METAMODEL_STORMS_PER_TASK)
            .zip(draws.storms.chunks(METAMODEL_STORMS_PER_TASK))
            .enumerate()
            .map(|(chunk, (rows, storms))| {
                let task = TaskRequest::MetamodelStorms(MetamodelStorms {
                    metamodel_id: self.metamodel_id.clone(),
                    seed: draws.seed,
                    responses: responses.to_vec(),
                    on_divergence: draws.on_divergence,
                    rows: rows.to_vec(),
                    storms: storms.to_vec(),
                    first: chunk * METAMODEL_STORMS_PER_TASK,
                });
                serde_json::to_string(&task).expect("a task serialises")
            })
            .collect();
        let done = |tasks: usize| {
            observer.progress(Progress::Samples { done: (tasks * METAMODEL_STORMS_PER_TASK).min(total), total })
        };
        let mut peaks = Vec::with_capacity(total);
        for output in self.tasks.run(&requests, observer, done)? {
            let stored: Vec<Vec<Option<f64>>> = read_output(&output)?;
            peaks.extend(stored.into_iter().map(|row| row.into_iter().map(|p| p.unwrap_or(f64::INFINITY)).collect()));
        }
        if peaks.len() != total {
            return Err(Error::Internal(format!("{} metamodel storms came back of {total}", peaks.len())));
        }
        Ok(peaks)
    }
}
