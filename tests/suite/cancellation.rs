//! A stop request reaches every long loop of a full-size calibration and of sampling within about
//! a second: the work is cancelled once it reports a given stage, and the time from the request
//! to the work's return is measured.
//!
//! The bound is 2 s, "about a second" with room for a loaded 2-core machine: the checks sit
//! between pieces of work of a few milliseconds (4096 integration steps, one refinement iteration,
//! one candidate structure, one row of an expansion's Gram matrix, a batch of 8 sampled storms),
//! so a working stop returns in milliseconds and a missing one takes the rest of the stage
//! (seconds to a minute at this size).

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use windmeta::analysis::{OnThisMachine, Response, metamodel_peaks};
use windmeta::error::Error;
use windmeta::progress::{Observer, Progress, Silent};
use windmeta::study::Study;
use windmeta::surrogate::assembly::{assemble, fit_expansions};
use windmeta::surrogate::phases::{fit_experiments, plan};
use windmeta::surrogate::{CalibrationOptions, calibrate};

const LATENCY_BOUND: Duration = Duration::from_secs(2);

/// Which progress report marks a stage.
type Trigger = fn(&Progress) -> bool;

/// Asks the work to stop the first time `trigger` accepts a progress report.
struct StopAt {
    trigger: Trigger,
    stop: AtomicBool,
    asked: Mutex<Option<Instant>>,
}

impl StopAt {
    fn new(trigger: Trigger) -> Self {
        StopAt { trigger, stop: AtomicBool::new(false), asked: Mutex::new(None) }
    }

    /// Time from the stop request to now.
    fn latency(&self) -> Duration {
        self.asked.lock().unwrap().expect("the stage was reached").elapsed()
    }
}

impl Observer for StopAt {
    fn progress(&self, progress: Progress) {
        if (self.trigger)(&progress) && !self.stop.load(Ordering::Relaxed) {
            *self.asked.lock().unwrap() = Some(Instant::now());
            self.stop.store(true, Ordering::Relaxed);
        }
    }
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

fn study() -> Study {
    Study::preset("frame40-kn").unwrap()
}

/// Four experiments beyond the twenty of the structure selection, so that every stage is reached.
fn options() -> CalibrationOptions {
    CalibrationOptions { experiments: 24, seed: 1, ..Default::default() }
}

/// Runs `work` under an observer that stops it at `trigger`, and checks that it stopped, soon.
fn stops_soon<T>(stage: &str, trigger: Trigger, work: impl FnOnce(&StopAt) -> windmeta::error::Result<T>) {
    let observer = StopAt::new(trigger);
    let outcome = work(&observer);
    let latency = observer.latency();
    eprintln!("{stage}: stopped {:.0} ms after the request", latency.as_secs_f64() * 1e3);
    assert!(matches!(outcome, Err(Error::Cancelled)), "{stage}: {:?}", outcome.map(|_| "finished"));
    assert!(latency < LATENCY_BOUND, "{stage}: {latency:?}");
}

#[test]
fn a_stop_reaches_every_stage_within_about_a_second() {
    let study = study();
    let options = options();
    assert_eq!(options.selection_experiments, 20, "the third trigger counts on 20 selection experiments");
    // Selection storms: wind generation and integration of the reference model.
    let first_storm: Trigger = |p| matches!(p, Progress::Experiments { done: 1, .. });
    stops_soon("reference storms", first_storm, |observer| calibrate(&study, &options, observer));
    // NARX structure selection over the candidates.
    let selection: Trigger = |p| matches!(p, Progress::Structure { mode: 1 });
    stops_soon("structure selection", selection, |observer| calibrate(&study, &options, observer));
    // The later stages run the calibration's own phases from one plan, instead of planning again
    // for each: the other storms with the refinement of their coefficients (reported after the
    // selection's twenty), then the polynomial chaos expansions.
    let planned = plan(&study, &options, &Silent).unwrap();
    let remaining = planned.plan.remaining();
    let storms: Trigger = |p| matches!(p, Progress::Experiments { done: 21, .. });
    stops_soon("storms and refinement", storms, |observer| {
        fit_experiments(&study, &options, &planned.plan, &remaining, 20, observer)
    });
    let mut fits = planned.fit_selection(&options, &Silent).unwrap();
    fits.extend(fit_experiments(&study, &options, &planned.plan, &remaining, 20, &Silent).unwrap());
    let expansions: Trigger = |p| matches!(p, Progress::Expansion { mode: 1 });
    stops_soon("expansions", expansions, |observer| {
        let expand = |targets: &[Vec<f64>]| fit_expansions(&study, &options, &planned.plan.design, targets, observer);
        assemble(&study, &options, &planned, fits, planned.seconds.clone(), &expand, observer)
    });

    // The shared fixture, calibrated on two-minute storms (the NARX models do not depend on the
    // storm's length), samples full-size storms.
    let metamodel = &crate::harness::fixture::metamodel().0;
    let observer = StopAt::new(|p| matches!(p, Progress::Samples { .. }));
    let roof = Response::Displacement { floor: study.structure.floors() };
    let outcome = metamodel_peaks(metamodel, &study, &study.inputs, 100_000, 1, roof, &OnThisMachine, &observer);
    let latency = observer.latency();
    eprintln!("sampling: stopped {:.0} ms after the request", latency.as_secs_f64() * 1e3);
    assert!(matches!(outcome, Err(Error::Cancelled)));
    assert!(latency < LATENCY_BOUND, "sampling: {latency:?}");
}
