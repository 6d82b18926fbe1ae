//! `windmeta simulate`: one storm through the reference model.

use super::ProblemArgs;
use crate::analysis::{RESPONSE_KINDS, Response, STANDARD_GRAVITY, profile_responses, reference_peak};
use crate::error::{Error, Result};
use crate::problem::{Order, WindPath};
use crate::uncertainty::rng_from_seed;
use clap::{Args, ValueEnum};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum WindChoice {
    /// Every floor's speed, projected on the modes.
    Field,
    /// The modal forces directly from the projected spectrum (equal in law, faster).
    Modal,
}

#[derive(Debug, Clone, Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub problem: ProblemArgs,
    /// Seed of the wind's random phases.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Integrate every floor (Newmark) instead of the retained modes; uses the floor field.
    #[arg(long)]
    pub full_order: bool,
    /// Wind path of a reduced-order run.
    #[arg(long, value_enum, default_value = "modal")]
    pub wind: WindChoice,
    /// Write the roof displacement history (CSV: t_s, roof_m).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub json: bool,
}

pub fn simulate(args: &SimulateArgs) -> Result<String> {
    let started = Instant::now();
    let problem = args.problem.problem()?;
    let setup_seconds = started.elapsed().as_secs_f64();
    // Every input that is not fixed sits at its mean.
    let x = problem.inputs.means();
    let order = if args.full_order { Order::Full } else { Order::Reduced };
    let path = match (order, args.wind) {
        (Order::Full, _) | (_, WindChoice::Field) => WindPath::Field,
        _ => WindPath::Modal,
    };
    let run = problem.reference_run(&x, order, path, &mut rng_from_seed(args.seed))?;
    let dt = problem.storm.time_step;
    let (peak_index, peak) = run
        .roof
        .iter()
        .enumerate()
        .fold((0, 0.0f64), |(bi, b), (i, v)| if v.abs() > b { (i, v.abs()) } else { (bi, b) });
    if let Some(path) = &args.out {
        let mut writer =
            csv::Writer::from_path(path).map_err(|e| Error::invalid("out", format!("{}: {e}", path.display())))?;
        writer.write_record(["t_s", "roof_m"]).map_err(|e| Error::invalid("out", e.to_string()))?;
        for (i, u) in run.roof.iter().enumerate() {
            writer
                .write_record([format!("{:.4}", i as f64 * dt), format!("{u:.9e}")])
                .map_err(|e| Error::invalid("out", e.to_string()))?;
        }
        writer.flush().map_err(|e| Error::invalid("out", e.to_string()))?;
    }
    // Every response at every floor where it exists (a full-order run has no accelerations).
    let mut peaks = serde_json::Map::new();
    let mut largest = Vec::new();
    for kind in RESPONSE_KINDS {
        if kind == "acceleration" && args.full_order {
            continue;
        }
        let responses = profile_responses(kind, &problem)?;
        let values = responses.iter().map(|&r| reference_peak(&problem, &x, &run, r)).collect::<Result<Vec<f64>>>()?;
        let (at, most) = responses
            .iter()
            .zip(&values)
            .fold((responses[0], 0.0), |best, (r, v)| if *v > best.1 { (*r, *v) } else { best });
        largest.push((at, most));
        let floors: Vec<usize> = responses.iter().map(Response::floor).collect();
        peaks.insert(kind.to_string(), json!({"unit": responses[0].unit(), "floors": floors, "peaks": values}));
    }
    let inputs: serde_json::Map<String, serde_json::Value> =
        problem.inputs.names().zip(&x).map(|(n, v)| (n.to_string(), json!(v))).collect();
    let order_name = if args.full_order { "full" } else { "reduced" };
    let path_name = match path {
        WindPath::Field => "field",
        WindPath::Modal => "modal",
    };
    if args.json {
        let value = json!({
            "preset": problem.name,
            "order": order_name,
            "wind": path_name,
            "seed": args.seed,
            "duration_s": problem.storm.duration,
            "time_step_s": dt,
            "inputs": inputs,
            "peak_roof_displacement_m": peak,
            "peak_time_s": peak_index as f64 * dt,
            "mean_roof_displacement_m": run.roof.iter().sum::<f64>() / run.roof.len() as f64,
            "peaks": peaks,
            "timings_s": {"setup": setup_seconds, "wind": run.wind_seconds, "integration": run.integration_seconds},
        });
        return Ok(serde_json::to_string_pretty(&value).expect("plain JSON"));
    }
    let mut out = format!(
        "{} storm of {} s at Δt = {} s, {order_name}-order, {path_name} wind, seed {}\n",
        problem.name, problem.storm.duration, dt, args.seed
    );
    for (name, value) in &inputs {
        out += &format!("  {name:<15} {value}\n");
    }
    out += &format!("peak roof displacement  {peak:.4} m at t = {:.2} s\n", peak_index as f64 * dt);
    out += "largest peaks up the height (every floor's in --json):\n";
    for (response, value) in &largest {
        out += &format!("  {:<45} {value:.5} {}", response.describe(), response.unit());
        if let Response::Acceleration { .. } = response {
            out += &format!(" ({:.2} milli-g)", value / STANDARD_GRAVITY * 1e3);
        }
        out += "\n";
    }
    out += &format!(
        "time: setup {:.3} s, wind {:.3} s, integration {:.3} s\n",
        setup_seconds, run.wind_seconds, run.integration_seconds
    );
    if let Some(path) = &args.out {
        out += &format!("roof history written to {}\n", path.display());
    }
    Ok(out)
}
