//! `windmeta simulate`: one storm through the reference model.

use super::StudyArgs;
use crate::analysis::{Response, ResponseKind, STANDARD_GRAVITY, profile_responses, reference_history, reference_peak};
use crate::error::{Error, Result};
use crate::study::{Order, Study, WindPath};
use crate::uncertainty::rng_from_seed;
use clap::{Args, ValueEnum};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum WindChoice {
    /// Every floor's speed, projected on the modes.
    Field,
    /// The modal forces directly from the projected spectrum (equal in law, faster).
    Modal,
}

/// What `windmeta simulate` runs and which histories it writes.
#[derive(Debug, Clone, Args)]
pub struct SimulateArgs {
    /// The study whose reference model is run.
    #[command(flatten)]
    pub study: StudyArgs,
    /// Seed of the wind's random phases.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Integrate every floor (Newmark) instead of the retained modes; uses the floor field.
    #[arg(long)]
    pub full_order: bool,
    /// Wind path of a reduced-order run.
    #[arg(long, value_enum, default_value = "modal")]
    pub wind: WindChoice,
    /// Write response histories (CSV: t_s, then a column per response such as
    /// acceleration_40_m_s2); the roof displacement unless --history or --history-floors say otherwise.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A response whose history --out writes: displacement, drift, acceleration, damper_force or
    /// damper_stroke (repeatable).
    #[arg(long = "history", value_name = "KIND")]
    pub histories: Vec<String>,
    /// The floors of those histories: `all` (every floor where the response exists) or a list
    /// such as 1,20,40; the roof when absent.
    #[arg(long, value_name = "all|F1,F2,...")]
    pub history_floors: Option<String>,
    /// Print the inputs, every floor's peaks and the timings as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `windmeta simulate`: one storm at the inputs' means (or fixed values) and its peaks.
pub fn simulate(args: &SimulateArgs) -> Result<String> {
    if args.study.is_spatial() {
        return super::simulate_spatial::simulate_spatial(args);
    }
    let started = Instant::now();
    let study = args.study.study()?;
    let setup_seconds = started.elapsed().as_secs_f64();
    // Every input that is not fixed sits at its mean.
    let x = study.inputs.means();
    let order = if args.full_order { Order::Full } else { Order::Reduced };
    let path = match (order, args.wind) {
        (Order::Full, _) | (_, WindChoice::Field) => WindPath::Field,
        _ => WindPath::Modal,
    };
    let run = study.reference_run(&x, order, path, &mut rng_from_seed(args.seed))?;
    let dt = study.storm.time_step;
    let (peak_index, peak) = run
        .roof
        .iter()
        .enumerate()
        .fold((0, 0.0f64), |(bi, b), (i, v)| if v.abs() > b { (i, v.abs()) } else { (bi, b) });
    if let Some(path) = &args.out {
        let responses = history_responses(args, &study)?;
        let histories =
            responses.iter().map(|&r| reference_history(&study, &x, &run, r)).collect::<Result<Vec<Vec<f64>>>>()?;
        let columns: Vec<String> = responses
            .iter()
            .map(|r| {
                format!("{}_{}_{}", r.kind().name(), r.floor().map_or(String::new(), |f| f.to_string()), r.unit_tag())
            })
            .collect();
        write_histories(path, &columns, &histories, dt)?;
    }
    // Every response at every floor where it exists.
    let mut peaks = serde_json::Map::new();
    let mut largest = Vec::new();
    for kind in ResponseKind::ALL {
        let responses = profile_responses(kind, &study)?;
        let values = responses.iter().map(|&r| reference_peak(&study, &x, &run, r)).collect::<Result<Vec<f64>>>()?;
        let (at, most) = responses
            .iter()
            .zip(&values)
            .fold((responses[0], 0.0), |best, (r, v)| if *v > best.1 { (*r, *v) } else { best });
        largest.push((at, most));
        let floors: Vec<usize> = responses.iter().filter_map(Response::floor).collect();
        peaks.insert(kind.name().to_string(), json!({"unit": responses[0].unit(), "floors": floors, "peaks": values}));
    }
    let inputs: serde_json::Map<String, serde_json::Value> =
        study.inputs.names().zip(&x).map(|(n, v)| (n.to_string(), json!(v))).collect();
    let order_name = if args.full_order { "full" } else { "reduced" };
    let path_name = match path {
        WindPath::Field => "field",
        WindPath::Modal => "modal",
    };
    if args.json {
        let value = json!({
            "preset": study.name,
            "order": order_name,
            "wind": path_name,
            "seed": args.seed,
            "duration_s": study.storm.duration,
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
        study.name, study.storm.duration, dt, args.seed
    );
    for (name, value) in &inputs {
        out += &format!("  {name:<15} {value}\n");
    }
    out += &format!("peak roof displacement  {peak:.4} m at t = {:.2} s\n", peak_index as f64 * dt);
    out += "largest peaks up the height (every floor's in --json):\n";
    for (response, value) in &largest {
        out += &format!("  {:<45} {value:.5} {}", response.describe(), response.unit());
        if response.is_acceleration() {
            out += &format!(" ({:.2} milli-g)", value / STANDARD_GRAVITY * 1e3);
        }
        out += "\n";
    }
    out += &format!(
        "time: setup {:.3} s, wind {:.3} s, integration {:.3} s\n",
        setup_seconds, run.wind_seconds, run.integration_seconds
    );
    if let Some(path) = &args.out {
        out += &format!("histories written to {}\n", path.display());
    }
    Ok(out)
}

/// The responses whose histories `--out` writes: each `--history` kind (displacement by default)
/// at each of `--history-floors` (the roof by default; `all`: every floor where it exists).
fn history_responses(args: &SimulateArgs, study: &Study) -> Result<Vec<Response>> {
    let kinds = if args.histories.is_empty() {
        vec![ResponseKind::Displacement]
    } else {
        args.histories.iter().map(|k| ResponseKind::parse(k)).collect::<Result<_>>()?
    };
    if kinds.contains(&ResponseKind::RmsAcceleration) {
        return Err(Error::invalid(
            "history",
            "an RMS acceleration is one value per storm (in the run's peaks); its history is `acceleration`",
        ));
    }
    let mut responses = Vec::new();
    for kind in kinds {
        match history_floors(args)? {
            HistoryFloors::Roof => responses.push(kind.located(None, None, &study.structure)?),
            HistoryFloors::All => responses.extend(profile_responses(kind, study)?),
            HistoryFloors::These(floors) => {
                for floor in floors {
                    responses.push(kind.located(Some(floor), None, &study.structure)?);
                }
            }
        }
    }
    Ok(responses)
}

/// The floors `--history-floors` names.
pub(super) enum HistoryFloors {
    /// The roof (the default).
    Roof,
    /// Every floor where the response exists.
    All,
    /// These floors (1-based, unchecked).
    These(Vec<usize>),
}

/// Reads `--history-floors`: `all` or a list such as 1,20,40; the roof when absent.
pub(super) fn history_floors(args: &SimulateArgs) -> Result<HistoryFloors> {
    Ok(match args.history_floors.as_deref().map(str::trim) {
        None => HistoryFloors::Roof,
        Some("all") => HistoryFloors::All,
        Some(list) => HistoryFloors::These(
            list.split(',')
                .map(|floor| {
                    floor.trim().parse::<usize>().map_err(|_| {
                        Error::invalid(
                            "history-floors",
                            format!("`{floor}` is not a floor; give `all` or floors such as 1,20,40"),
                        )
                    })
                })
                .collect::<Result<_>>()?,
        ),
    })
}

/// Writes `histories` (one per column, `dt` apart) as CSV: t_s, then a column per response.
pub(super) fn write_histories(path: &Path, columns: &[String], histories: &[Vec<f64>], dt: f64) -> Result<()> {
    let failed = |e: csv::Error| Error::invalid("out", format!("{}: {e}", path.display()));
    let mut writer = csv::Writer::from_path(path).map_err(failed)?;
    let mut header = vec!["t_s".to_string()];
    header.extend(columns.iter().cloned());
    writer.write_record(&header).map_err(failed)?;
    let steps = histories.first().map_or(0, Vec::len);
    for t in 0..steps {
        let mut row = vec![format!("{:.4}", t as f64 * dt)];
        row.extend(histories.iter().map(|h| format!("{:.9e}", h[t])));
        writer.write_record(&row).map_err(failed)?;
    }
    writer.flush().map_err(|e| Error::invalid("out", format!("{}: {e}", path.display())))
}
