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
use windmeta::analysis::{Response, metamodel_peaks};
use windmeta::error::Error;
use windmeta::progress::{Observer, Progress};
use windmeta::study::Study;
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

#[test]
fn a_stop_reaches_every_stage_within_about_a_second() {
    let study = study();
    let options = options();
    let selection = options.selection_experiments;
    let stages: [(&str, Trigger); 4] = [
        // Selection storms: wind generation and integration of the reference model.
        ("reference storms", |p| matches!(p, Progress::Experiments { done: 1, .. })),
        // NARX structure selection over the candidates.
        ("structure selection", |p| matches!(p, Progress::Structure { mode: 1 })),
        // The other storms with the refinement of their coefficients (reported after the selection's).
        ("storms and refinement", |p| matches!(p, Progress::Experiments { done, .. } if *done == 21)),
        // Polynomial chaos expansions.
        ("expansions", |p| matches!(p, Progress::Expansion { mode: 1 })),
    ];
    assert_eq!(selection, 20, "the third trigger counts on 20 selection experiments");
    for (stage, trigger) in stages {
        let observer = StopAt::new(trigger);
        let outcome = calibrate(&study, &options, &observer);
        let latency = observer.latency();
        eprintln!("{stage}: stopped {:.0} ms after the request", latency.as_secs_f64() * 1e3);
        assert!(matches!(outcome, Err(Error::Cancelled)), "{stage}: {:?}", outcome.map(|_| "finished"));
        assert!(latency < LATENCY_BOUND, "{stage}: {latency:?}");
    }

    // The shared fixture, calibrated on two-minute storms (the NARX models do not depend on the
    // storm's length), samples full-size storms.
    let metamodel = &crate::harness::fixture::metamodel().0;
    let observer = StopAt::new(|p| matches!(p, Progress::Samples { .. }));
    let roof = Response::Displacement { floor: study.structure.floors() };
    let outcome = metamodel_peaks(metamodel, &study, &study.inputs, 100_000, 1, roof, &observer);
    let latency = observer.latency();
    eprintln!("sampling: stopped {:.0} ms after the request", latency.as_secs_f64() * 1e3);
    assert!(matches!(outcome, Err(Error::Cancelled)));
    assert!(latency < LATENCY_BOUND, "sampling: {latency:?}");
}
