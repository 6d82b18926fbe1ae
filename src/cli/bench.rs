//! `windmeta bench`: the method's costs side by side, measured in one run so that their ratios are
//! honest: a full calibration and its stages, the per-sample stages of one full-size storm (wind by
//! both paths, both reference integrators, the metamodel's free run on the same storm), and an
//! exceedance curve, roof-acceleration and RMS-acceleration curves, drift and acceleration profiles of every floor, an
//! annual curve with ten return levels, a serviceability check of the built-in criteria, a sweep of a
//! damper coefficient and Sobol indices end to end. Speed is measured here and in
//! `benches/`, never asserted in a test.

use crate::analysis::{
    BUILT_IN, CertifyOptions, HazardOptions, OnThisMachine, Response, ResponseKind, Sampling, ServiceabilityOptions,
    SweepOptions, WIND_SPEED, automatic_thresholds, built_in, certify_exceedance, exceedance_curve, metamodel_hazard,
    metamodel_peaks, metamodel_profiles, metamodel_sensitivity, metamodel_serviceability, metamodel_sweep,
};
use crate::dynamics::{Dampers, integrate_full, integrate_reduced};
use crate::error::{Error, Result};
use crate::progress::Silent;
use crate::simd::LANES;
use crate::structure::Modes;
use crate::structure::spatial::{SpatialModes, frame40_3d};
use crate::study::{Order, PhysicalParameters, Study, WindPath};
use crate::surrogate::{BatchWorkspace, CalibrationOptions, Metamodel, PEAK_BATCH, Reduction, calibrate};
use crate::uncertainty::{Marginal, latin_hypercube, rng_from_seed};
use crate::wind::{FloorForces, ForceSource, ModalForces, TransformWorkspace};
use clap::Args;
use serde::Serialize;
use std::time::Instant;

/// What `windmeta bench` measures and how often.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Preset to measure.
    #[arg(long, default_value = "frame40-kn")]
    pub preset: String,
    /// Repetitions of each per-sample stage; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repetitions: usize,
    /// Storm duration (s).
    #[arg(long, default_value_t = 900.0)]
    pub duration: f64,
    /// Experiments of the calibration that is measured and whose metamodel is then sampled.
    #[arg(long, default_value_t = 200)]
    pub experiments: usize,
    /// Samples of the exceedance curve.
    #[arg(long, default_value_t = 10_000)]
    pub samples: usize,
    /// Storms of the annual (hazard) curve, with the ten default-like return periods.
    #[arg(long, default_value_t = 20_000)]
    pub hazard_samples: usize,
    /// Rows N of the Sobol analysis (N·(groups + 2) storms).
    #[arg(long, default_value_t = 4096)]
    pub sensitivity_samples: usize,
    /// Reduced-order reference storms of the certified exceedance curve.
    #[arg(long, default_value_t = 200)]
    pub reference_storms: usize,
    /// Print the report as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl BenchArgs {
    /// Whether the sizes are those the targets are set for (the defaults).
    fn at_target_sizes(&self) -> bool {
        self.duration == 900.0
            && self.experiments == 200
            && self.samples == 10_000
            && self.hazard_samples == 20_000
            && self.sensitivity_samples == 4096
            && self.reference_storms == 200
    }
}

/// One measured stage.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    /// What was timed.
    pub stage: String,
    /// Median wall-clock time of the repetitions (s).
    pub median_seconds: f64,
    /// Times the stage was run.
    pub repetitions: usize,
}

/// A figure of the report against the target set for it at the default sizes.
#[derive(Debug, Clone, Serialize)]
pub struct BenchTarget {
    /// What is compared.
    pub figure: String,
    /// The measured value, in `unit`.
    pub measured: f64,
    /// The target, in `unit`: an upper bound for times and slowdowns, a lower one for speed-ups.
    pub target: f64,
    /// `s` for a time, `x` for a ratio.
    pub unit: &'static str,
    /// Whether the target is an upper bound (times, slowdowns) or a lower one (speed-ups).
    pub at_most: bool,
    /// Whether it is met; null where the run's sizes are not the defaults the target is set for.
    pub met: Option<bool>,
}

/// Everything `windmeta bench` measures.
#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    /// The preset measured.
    pub preset: String,
    /// Storm duration (s).
    pub duration_s: f64,
    /// The study's time step (s).
    pub time_step_s: f64,
    /// Threads of rayon's pool, used by the stages run on all threads.
    pub threads: usize,
    /// Experiments K of the measured calibration.
    pub experiments: usize,
    /// Samples of the measured exceedance curve.
    pub samples: usize,
    /// The stages in the order they ran.
    pub rows: Vec<BenchRow>,
    /// Reduced-order reference integration over the metamodel's free run, per sample, same storm,
    /// both on one thread.
    pub metamodel_speedup_vs_reduced_reference: f64,
    /// The reduced-order reference one storm at a time over the same storms in vector lanes, per
    /// storm, both on one thread.
    pub reference_lanes_speedup: f64,
    /// The exceedance curve of `samples` storms end to end, on all threads (named for the default
    /// 10 000 samples).
    pub exceedance_10k_seconds: f64,
    /// The calibration end to end, on all threads.
    pub calibration_seconds: f64,
    /// The figures with targets, each against its target.
    pub targets: Vec<BenchTarget>,
}

/// The wind speed (m/s) of the calm-storm acceleration row.
const CALM_WIND_SPEED: f64 = 5.0;

/// The return periods (years) of the benchmarked hazard answer.
const BENCH_RETURN_PERIODS: [f64; 10] = [2.0, 5.0, 10.0, 50.0, 100.0, 500.0, 700.0, 1000.0, 10000.0, 100000.0];

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) }
}

fn time<T>(repetitions: usize, mut f: impl FnMut(u64) -> Result<T>) -> Result<f64> {
    let mut seconds = Vec::with_capacity(repetitions);
    for r in 0..repetitions {
        let started = Instant::now();
        std::hint::black_box(f(r as u64)?);
        seconds.push(started.elapsed().as_secs_f64());
    }
    Ok(median(seconds))
}

/// Runs every measurement of [`BenchReport`].
pub fn bench_report(args: &BenchArgs) -> Result<BenchReport> {
    let repetitions = args.repetitions.max(1);
    let study = Study::preset(&args.preset)?.with_storm(args.duration, 0.01)?;
    let row = |stage: String, median_seconds: f64, repetitions: usize| BenchRow { stage, median_seconds, repetitions };
    let mut rows = Vec::new();

    let options = CalibrationOptions { experiments: args.experiments, ..Default::default() };
    let metamodel = calibrate(&study, &options, &Silent)?;
    let s = &metamodel.calibration.seconds;
    let k = args.experiments;
    rows.push(row(format!("calibration, K = {k}, end to end (all threads)"), s.total, 1));
    rows.push(row("  selection experiments through the reference".into(), s.experiments, 1));
    rows.push(row("  structure selection".into(), s.structure, 1));
    rows.push(row("  other experiments through the reference, NARX fits".into(), s.coefficients, 1));
    rows.push(row("  polynomial chaos expansions, diagnostics".into(), s.expansion, 1));

    let (per_sample, ratios) = per_sample_rows(&study, &metamodel, repetitions)?;
    rows.extend(per_sample);

    let roof = Response::Displacement { floor: study.structure.floors() };
    let exceedance = time(repetitions.min(3), |r| {
        let peaks =
            metamodel_peaks(&metamodel, &study, &study.inputs, args.samples, 1 + r, roof, &OnThisMachine, &Silent)?;
        Ok(exceedance_curve(&peaks, &automatic_thresholds(&peaks, 50), 0.95))
    })?;
    rows.push(row(
        format!("exceedance curve, {} samples, end to end (all threads)", args.samples),
        exceedance,
        repetitions.min(3),
    ));
    let certify = CertifyOptions { reference_storms: args.reference_storms, order: Order::Reduced };
    let certified = time(repetitions.min(3), |r| {
        let peaks =
            metamodel_peaks(&metamodel, &study, &study.inputs, args.samples, 1 + r, roof, &OnThisMachine, &Silent)?;
        let thresholds = automatic_thresholds(&peaks, 50);
        let inputs = &study.inputs;
        let runner = &OnThisMachine;
        certify_exceedance(
            &metamodel,
            &study,
            inputs,
            &peaks,
            &thresholds,
            Some(&certify),
            1 + r,
            roof,
            0.95,
            runner,
            &Silent,
        )
    })?;
    rows.push(row(
        format!(
            "certified exceedance curve, {} samples, {} reduced-order reference storms (all threads)",
            args.samples, args.reference_storms
        ),
        certified,
        repetitions.min(3),
    ));
    let floor = study.structure.floors();
    // The slowest wind speed for accelerations: the metamodel's recursion is the same, but the
    // sink of a calm storm was once 13 times slower than at 60 m/s.
    let calm = study.inputs.clone().with_marginal(WIND_SPEED, Marginal::Constant { value: CALM_WIND_SPEED })?;
    let mut slowest_response = 0.0f64;
    let mut calm_acceleration = 0.0;
    for (name, response, inputs) in [
        ("roof acceleration".to_string(), Response::Acceleration { floor }, &study.inputs),
        ("roof RMS acceleration".to_string(), Response::RmsAcceleration { floor }, &study.inputs),
        (format!("roof acceleration at {CALM_WIND_SPEED} m/s"), Response::Acceleration { floor }, &calm),
    ] {
        let seconds = time(repetitions.min(3), |r| {
            metamodel_peaks(&metamodel, &study, inputs, args.samples, 1 + r, response, &OnThisMachine, &Silent)
        })?;
        rows.push(row(
            format!("{name} exceedance peaks, {} samples (all threads)", args.samples),
            seconds,
            repetitions.min(3),
        ));
        if std::ptr::eq(inputs, &calm) {
            calm_acceleration = seconds;
        } else {
            slowest_response = slowest_response.max(seconds);
        }
    }
    for kind in [ResponseKind::Drift, ResponseKind::Acceleration] {
        let profile = time(repetitions.min(3), |r| {
            let inputs = &study.inputs;
            let samples =
                metamodel_profiles(&metamodel, &study, inputs, args.samples, 1 + r, kind, &OnThisMachine, &Silent)?;
            samples.quantile_profile(0.5, 0.95)
        })?;
        rows.push(row(
            format!(
                "{} profile, every floor, median with its band, {} samples (all threads)",
                kind.name(),
                args.samples
            ),
            profile,
            repetitions.min(3),
        ));
    }
    let hazard = HazardOptions {
        climate: *study.inputs.marginal(WIND_SPEED)?,
        samples: args.hazard_samples,
        seed: 1,
        thresholds: None,
        return_periods: BENCH_RETURN_PERIODS.to_vec(),
        limit: None,
        confidence: 0.95,
        sampling: Sampling::Stratified,
        certify: None,
    };
    let hazard_seconds =
        time(repetitions.min(3), |_| metamodel_hazard(&metamodel, &study, roof, &hazard, &OnThisMachine, &Silent))?;
    rows.push(row(
        format!(
            "hazard curve, {} storms, {} return periods (all threads)",
            args.hazard_samples,
            BENCH_RETURN_PERIODS.len()
        ),
        hazard_seconds,
        repetitions.min(3),
    ));
    let climate = *study.inputs.marginal(WIND_SPEED)?;
    let built_ins = BUILT_IN.iter().map(|name| built_in(name, study.structure.floors())).collect::<Result<Vec<_>>>()?;
    let check = ServiceabilityOptions {
        climate,
        criteria: built_ins,
        samples: args.hazard_samples,
        seed: 1,
        confidence: 0.95,
        certify: None,
    };
    let serviceability =
        time(repetitions.min(3), |_| metamodel_serviceability(&metamodel, &study, &check, &OnThisMachine, &Silent))?;
    rows.push(row(
        format!(
            "serviceability check, {} built-in criteria ({}), {} storms (all threads)",
            BUILT_IN.len(),
            BUILT_IN.join(", "),
            args.hazard_samples
        ),
        serviceability,
        repetitions.min(3),
    ));
    // The top damper group's coefficient over its calibrated range, where a structure has dampers.
    let groups = study.structure.damper_groups();
    let mut swept_seconds = None;
    if groups > 0 {
        let input = format!("damper_c{groups}");
        let [low, high] = metamodel.calibrated_range(&study, &input)?;
        let sweep = SweepOptions {
            values: (0..5).map(|k| low + (high - low) * k as f64 / 4.0).collect(),
            input,
            climate,
            return_period_years: 10.0,
            samples: args.hazard_samples / 2,
            seed: 1,
            confidence: 0.95,
        };
        let roof_acceleration = Response::Acceleration { floor: study.structure.floors() };
        let swept = time(repetitions.min(3), |_| {
            metamodel_sweep(&metamodel, &study, roof_acceleration, &sweep, &OnThisMachine, &Silent)
        })?;
        rows.push(row(
            format!(
                "sweep of {}, 5 values x {} storms, 10-year roof acceleration (all threads)",
                sweep.input, sweep.samples
            ),
            swept,
            repetitions.min(3),
        ));
        swept_seconds = Some(swept);
    }
    let n = args.sensitivity_samples;
    let sobol = time(repetitions.min(3), |r| {
        metamodel_sensitivity(&metamodel, &study, roof, n, 1 + r, 0.95, &OnThisMachine, &Silent)
    })?;
    rows.push(row(
        format!("Sobol indices, N = {n}, with bootstrap intervals (all threads)"),
        sobol,
        repetitions.min(3),
    ));
    let judged = args.at_target_sizes();
    let target = |figure: String, measured: f64, target: f64, unit: &'static str, at_most: bool| BenchTarget {
        figure,
        measured,
        target,
        unit,
        at_most,
        met: judged.then_some(if at_most { measured <= target } else { measured >= target }),
    };
    let (samples, hazard_samples) = (args.samples, args.hazard_samples);
    let mut targets = vec![
        target(format!("calibration, K = {k}"), s.total, 30.0, "s", true),
        target(
            "metamodel over the reduced reference one storm at a time, per storm".into(),
            ratios.metamodel,
            2000.0,
            "x",
            false,
        ),
        target(
            "reduced reference in lanes over one at a time, per storm".into(),
            ratios.reference_lanes,
            4.0,
            "x",
            false,
        ),
        target(format!("exceedance curve of the roof displacement, {samples} storms"), exceedance, 1.5, "s", true),
        target(
            format!("reduced reference of frame40-3d ({SPATIAL_MODES} modes) over the plane frame's, per storm"),
            ratios.spatial_reference,
            3.0,
            "x",
            true,
        ),
        target(
            format!("certified curve, {samples} storms with {} reference storms", args.reference_storms),
            certified,
            12.0,
            "s",
            true,
        ),
        target(
            "slowest response curve over the displacement curve".into(),
            slowest_response / exceedance,
            1.5,
            "x",
            true,
        ),
        target(
            format!("roof acceleration at {CALM_WIND_SPEED} m/s over the displacement curve"),
            calm_acceleration / exceedance,
            1.5,
            "x",
            true,
        ),
        target(format!("annual curve, {hazard_samples} storms"), hazard_seconds, 4.0, "s", true),
        target(
            format!("serviceability check of the three built-ins, {hazard_samples} storms"),
            serviceability,
            10.0,
            "s",
            true,
        ),
        target(format!("Sobol indices, N = {n}"), sobol, 8.0, "s", true),
    ];
    if let Some(swept) = swept_seconds {
        targets.push(target(
            format!("sweep of five values, {} storms each", hazard_samples / 2),
            swept,
            15.0,
            "s",
            true,
        ));
    }
    Ok(BenchReport {
        preset: args.preset.clone(),
        duration_s: args.duration,
        time_step_s: study.storm.time_step,
        threads: rayon::current_num_threads(),
        experiments: k,
        samples: args.samples,
        rows,
        metamodel_speedup_vs_reduced_reference: ratios.metamodel,
        reference_lanes_speedup: ratios.reference_lanes,
        exceedance_10k_seconds: exceedance,
        calibration_seconds: s.total,
        targets,
    })
}

/// Speed ratios of the per-sample stages.
struct PerSampleRatios {
    /// The reduced reference's time over the metamodel's, on the same storm.
    metamodel: f64,
    /// The reduced reference one storm at a time over the same storms in vector lanes.
    reference_lanes: f64,
    /// The three-dimensional building's reduced reference (six modes) over the plane frame's, on
    /// the same storm.
    spatial_reference: f64,
}

/// Modes of the three-dimensional building's reduced reference in the bench, the first six: the
/// plane frame's first two in x and in y, the first twist and the third in x.
const SPATIAL_MODES: usize = 6;

/// The direction of the drag on the three-dimensional preset, (0.6, 0.8): 53° from x, so that every
/// damper works (along an axis, the other direction's dampers sit at rounding-level velocities,
/// where the damper solve's Newton iterations are many: four times the cost, measured).
const SPATIAL_DRAG_DIRECTION: [f64; 2] = [0.6, 0.8];

/// The three-dimensional preset at a sample's parameters, driven by twice the plane storm's drag
/// (its plan is twice the frame's wind width) along [`SPATIAL_DRAG_DIRECTION`]: what its reduced
/// reference integrates.
struct SpatialStorm {
    modes: Modes,
    dampers: Dampers,
    forces: ModalForces,
}

impl SpatialStorm {
    fn new(study: &Study, params: &PhysicalParameters, plane_forces: &FloorForces) -> Result<Self> {
        let structure = frame40_3d([0.0, 0.0])?;
        let modes = SpatialModes::of(&structure, SPATIAL_MODES)?
            .modes()
            .scaled(params.youngs_modulus / structure.reference_youngs_modulus, params.mass_factor);
        let dampers = Dampers::spatial(&structure, &params.damper_coefficients, study.damper_exponent)?;
        let forces = plane_forces
            .scaled(2.0)
            .on_plan(SPATIAL_DRAG_DIRECTION, &structure.centres_of_mass)
            .project(modes.shapes.as_ref());
        Ok(SpatialStorm { modes, dampers, forces })
    }
}

/// Per-sample stages of one storm at the inputs' means, each on one thread, and of a design's
/// storms through the reduced reference one at a time and in lanes; returns the rows and ratios.
fn per_sample_rows(
    study: &Study,
    metamodel: &Metamodel,
    repetitions: usize,
) -> Result<(Vec<BenchRow>, PerSampleRatios)> {
    let p = study;
    let x = p.inputs.means();
    let params = p.parameters(&x)?;
    let shapes = p.modes.shapes.as_ref();
    let dampers = p.dampers(&params)?;
    let dt = p.storm.time_step;
    let floor_forces = p.wind.floor_forces(params.wind_speed, &p.storm, &mut rng_from_seed(1))?;
    let mut wind_workspace = TransformWorkspace::default();
    let coarse =
        p.modal_wind.simulate(params.wind_speed, p.storm.duration, &mut wind_workspace, &mut rng_from_seed(1))?;
    let modal_forces = coarse.on_grid(&p.storm);
    let modes = p.sample_modes(&params);
    let system = p.full_system(&params);
    let weights = Response::Displacement { floor: p.structure.floors() }
        .modal_weights(&metamodel.modes.shapes, &p.structure)?
        .expect("a displacement is a combination of the modes");
    // A design's storms, unlike one another as a calibration's are, for the reference in lanes.
    let design_storms = latin_hypercube(&p.inputs, LANES, &mut rng_from_seed(1))
        .iter()
        .enumerate()
        .map(|(k, x)| {
            let sample = p.parameters(x)?;
            let forces = p.modal_forces(&sample, WindPath::Modal, &mut rng_from_seed(k as u64))?;
            Ok((sample, forces))
        })
        .collect::<Result<Vec<_>>>()?;
    let batch: Vec<(usize, &[f64], &dyn ForceSource)> =
        (0..PEAK_BATCH).map(|k| (k, &x[..], &coarse as &dyn ForceSource)).collect();
    let building = SpatialStorm::new(p, &params, &floor_forces)?;

    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| Error::Internal(format!("a one-thread pool: {e}")))?;
    single.install(|| {
        let row = |stage: &str, median_seconds: f64| BenchRow { stage: stage.into(), median_seconds, repetitions };
        let field = time(repetitions, |r| {
            Ok(p.wind.floor_forces(params.wind_speed, &p.storm, &mut rng_from_seed(r))?.project(shapes))
        })?;
        let modal_coarse = time(repetitions, |r| {
            p.modal_wind.simulate(params.wind_speed, p.storm.duration, &mut wind_workspace, &mut rng_from_seed(r))
        })?;
        let modal_grid =
            time(repetitions, |r| p.modal_wind.forces(params.wind_speed, &p.storm, &mut rng_from_seed(r)))?;
        let reduced = time(repetitions, |_| {
            integrate_reduced(&modes, params.damping_ratio, &dampers, &modal_forces, dt, &Silent)
        })?;
        let design_alone = time(repetitions, |_| {
            design_storms
                .iter()
                .map(|(sample, forces)| {
                    let (modes, dampers) = (p.sample_modes(sample), p.dampers(sample)?);
                    integrate_reduced(&modes, sample.damping_ratio, &dampers, forces, dt, &Silent)
                })
                .collect::<Result<Vec<_>>>()
        })? / LANES as f64;
        let design_lanes = time(repetitions, |_| p.integrate_reduced_batch(&design_storms, &Silent))? / LANES as f64;
        let full = time(repetitions, |_| integrate_full(&system, &dampers, &floor_forces, dt, &Silent))?;
        let spatial = time(repetitions, |_| {
            integrate_reduced(&building.modes, params.damping_ratio, &building.dampers, &building.forces, dt, &Silent)
        })?;
        let mut workspace = BatchWorkspace::default();
        let metamodel_batch =
            time(repetitions, |_| metamodel.peaks(p, &batch, &Reduction::Combination(&weights), &mut workspace))?;
        let per_metamodel = metamodel_batch / PEAK_BATCH as f64;
        let rows = vec![
            row("per sample: wind, full field (40 floors) + projection", field),
            row("per sample: wind, modal fast path (3 modes), generation grid", modal_coarse),
            row("per sample: wind, modal fast path, interpolated to the storm grid", modal_grid),
            row("per sample: reduced-order reference integration (3 modes)", reduced),
            row(
                &format!("per sample: reduced-order reference, {LANES} storms of a design one at a time"),
                design_alone,
            ),
            row(&format!("per sample: reduced-order reference, the same {LANES} storms in vector lanes"), design_lanes),
            row("per sample: full-order reference integration (40 floors)", full),
            row(
                &format!(
                    "per sample: reduced-order reference of frame40-3d ({SPATIAL_MODES} modes, {} dampers), the same storm at 53° to x",
                    building.dampers.len()
                ),
                spatial,
            ),
            row(
                &format!(
                    "per sample: metamodel free run, {PEAK_BATCH} storms (two batches side by side), peak included"
                ),
                per_metamodel,
            ),
        ];
        Ok((
            rows,
            PerSampleRatios {
                metamodel: reduced / per_metamodel,
                reference_lanes: design_alone / design_lanes,
                spatial_reference: spatial / reduced,
            },
        ))
    })
}

/// Runs `windmeta bench`: the report as a Markdown table, or as JSON with `--json`.
pub fn bench(args: &BenchArgs) -> Result<String> {
    let report = bench_report(args)?;
    if args.json {
        return Ok(serde_json::to_string_pretty(&report).expect("plain JSON"));
    }
    Ok(table(&report))
}

/// The report as a Markdown table, medians in milliseconds, and the three headline figures.
pub fn table(report: &BenchReport) -> String {
    let mut out = format!(
        "{}, {} s storms at Δt = {} s, {} threads; per-sample stages on one thread\n\n",
        report.preset, report.duration_s, report.time_step_s, report.threads
    );
    out += "| stage | median (ms) | runs |\n|---|---:|---:|\n";
    for r in &report.rows {
        out += &format!("| {} | {:.3} | {} |\n", r.stage, r.median_seconds * 1e3, r.repetitions);
    }
    out += "\n| figure | measured | target | met |\n|---|---:|---:|---|\n";
    for t in &report.targets {
        let bound = if t.at_most { "≤" } else { "≥" };
        let met = match t.met {
            Some(true) => "yes",
            Some(false) => "NO",
            None => "not judged (sizes differ from the defaults)",
        };
        out += &format!("| {} | {:.2} {} | {bound} {} {} | {met} |\n", t.figure, t.measured, t.unit, t.target, t.unit);
    }
    out += &format!(
        "\nmetamodel vs reduced-order reference, per sample: {:.0}×\nreduced-order reference in lanes vs one at a time, per storm: {:.1}×\nexceedance curve of {} samples: {:.2} s\ncalibration, K = {}: {:.1} s\n",
        report.metamodel_speedup_vs_reduced_reference,
        report.reference_lanes_speedup,
        report.samples,
        report.exceedance_10k_seconds,
        report.experiments,
        report.calibration_seconds
    );
    out
}
