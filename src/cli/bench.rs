//! `windmeta bench`: medians of the stages of one full-size storm, measured in one run so that
//! their ratios are honest. Speed is measured here and in `benches/`, never asserted in a test.

use crate::dynamics::{FullSystem, integrate_full, integrate_reduced};
use crate::error::Result;
use crate::problem::Problem;
use crate::uncertainty::rng_from_seed;
use clap::Args;
use serde::Serialize;
use serde_json::json;
use std::time::Instant;

#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Preset to measure.
    #[arg(long, default_value = "frame40-kn")]
    pub preset: String,
    /// Repetitions per stage; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repetitions: usize,
    /// Storm duration (s).
    #[arg(long, default_value_t = 900.0)]
    pub duration: f64,
    #[arg(long)]
    pub json: bool,
}

/// One measured stage.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    pub stage: String,
    pub median_seconds: f64,
    pub repetitions: usize,
}

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

/// Per-realization stages at the inputs' means: wind by both paths, both reference integrators.
pub fn physics_rows(preset: &str, duration: f64, repetitions: usize) -> Result<Vec<BenchRow>> {
    let p = Problem::preset(preset)?.with_storm(duration, 0.01)?;
    let x = p.inputs.means();
    let params = p.parameters(&x)?;
    let shapes = p.modes.shapes.as_ref();
    let dampers = p.dampers(&params)?;
    let dt = p.storm.time_step;
    let floor_forces = p.wind.floor_forces(params.wind_speed, &p.storm, &mut rng_from_seed(1))?;
    let modal_forces = floor_forces.project(shapes);
    let modes = p.sample_modes(&params);
    let system = FullSystem::new(
        &p.structure,
        &p.all_modes,
        p.stiffness_factor(&params),
        params.mass_factor,
        params.damping_ratio,
    );
    let row = |stage: &str, median_seconds: f64| BenchRow { stage: stage.into(), median_seconds, repetitions };
    Ok(vec![
        row(
            "wind, full field (40 floors) + projection",
            time(repetitions, |r| {
                Ok(p.wind.floor_forces(params.wind_speed, &p.storm, &mut rng_from_seed(r))?.project(shapes))
            })?,
        ),
        row(
            "wind, modal fast path (3 modes)",
            time(repetitions, |r| p.wind.modal_forces(params.wind_speed, shapes, &p.storm, &mut rng_from_seed(r)))?,
        ),
        row(
            "reduced-order integration (3 modes)",
            time(repetitions, |_| integrate_reduced(&modes, params.damping_ratio, &dampers, &modal_forces, dt))?,
        ),
        row(
            "full-order integration (40 floors)",
            time(repetitions, |_| integrate_full(&system, &dampers, &floor_forces, dt))?,
        ),
    ])
}

pub fn bench(args: &BenchArgs) -> Result<String> {
    let rows = physics_rows(&args.preset, args.duration, args.repetitions.max(1))?;
    if args.json {
        return Ok(serde_json::to_string_pretty(
            &json!({"preset": args.preset, "duration_s": args.duration, "rows": rows}),
        )
        .expect("plain JSON"));
    }
    Ok(table(&args.preset, args.duration, &rows))
}

/// The rows as a Markdown table, medians in milliseconds and as a multiple of the fastest row.
pub fn table(preset: &str, duration: f64, rows: &[BenchRow]) -> String {
    let fastest = rows.iter().map(|r| r.median_seconds).fold(f64::INFINITY, f64::min);
    let mut out = format!(
        "{preset}, one {duration} s storm at Δt = 0.01 s, median of {} runs\n\n",
        rows.first().map_or(0, |r| r.repetitions)
    );
    out += "| stage | median (ms) | × fastest |\n|---|---:|---:|\n";
    for r in rows {
        out += &format!("| {} | {:.1} | {:.1} |\n", r.stage, r.median_seconds * 1e3, r.median_seconds / fastest);
    }
    out
}
