//! `windmeta simulate` of a three-dimensional building: one storm from a direction through its
//! reference model, and every floor's peaks per direction, in twist and at its worst corner.

use super::simulate::{HistoryFloors, SimulateArgs, history_floors, write_histories};
use crate::analysis::{STANDARD_GRAVITY, SpatialKind, SpatialResponse};
use crate::error::{Error, Result};
use crate::structure::spatial::Dof;
use crate::study::{FloorPeaks, Order, SpatialRun, SpatialStudy};
use crate::uncertainty::rng_from_seed;
use crate::wind::aerodynamic::Aerodynamics;
use serde_json::json;
use std::time::Instant;

/// One column of the floors' peaks.
type Column<'a> = &'a dyn Fn(&FloorPeaks) -> f64;

/// Runs `windmeta simulate` on a three-dimensional preset: one storm at the inputs' means (the
/// direction's mean is 180° unless fixed) and its peaks.
pub fn simulate_spatial(args: &SimulateArgs) -> Result<String> {
    let started = Instant::now();
    let study = args.study.spatial_study()?;
    // Checked before the storm runs.
    let histories = match &args.out {
        Some(_) => history_responses(args, &study)?,
        None if !args.histories.is_empty() || args.history_floors.is_some() => {
            return Err(Error::invalid("out", "--history and --history-floors need --out FILE"));
        }
        None => Vec::new(),
    };
    let x = study.inputs.means();
    let order = if args.full_order { Order::Full } else { Order::Reduced };
    let setup_seconds = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let run = study.reference_run(&x, order, &mut rng_from_seed(args.seed))?;
    let run_seconds = started.elapsed().as_secs_f64();
    if let Some(path) = &args.out {
        write_spatial_histories(path, &histories, &run, &study)?;
    }
    let peaks = run.floor_peaks(&study.structure, study.storm.time_step);
    let eccentricity = study.parameters(&x)?.eccentricity;
    let inputs: serde_json::Map<String, serde_json::Value> =
        study.inputs.names().zip(&x).map(|(n, v)| (n.to_string(), json!(v))).collect();
    let order_name = if args.full_order { "full" } else { "reduced" };
    let aerodynamics = study.wind.aerodynamics();
    let loads = aerodynamics.map_or("the drag alone", Aerodynamics::describe);
    // Records are taken at the direction measured nearest to the storm's.
    let records_direction = match aerodynamics {
        Some(Aerodynamics::Records(records)) => Some(records.nearest(run.direction)?.1),
        _ => None,
    };
    let corners = study.structure.plans[0].corners();
    if args.json {
        let column = |f: &dyn Fn(&FloorPeaks) -> f64| peaks.iter().map(f).collect::<Vec<f64>>();
        let value = json!({
            "preset": study.name,
            "order": order_name,
            "wake_loads": aerodynamics.map_or("none", Aerodynamics::name),
            "records_direction_deg": records_direction,
            "eccentricity_m": eccentricity,
            "seed": args.seed,
            "duration_s": study.storm.duration,
            "time_step_s": study.storm.time_step,
            "inputs": inputs,
            "floors": (1..=peaks.len()).collect::<Vec<_>>(),
            "peaks": {
                "displacement_x_m": column(&|p| p.displacement[0]),
                "displacement_y_m": column(&|p| p.displacement[1]),
                "rotation_rad": column(&|p| p.displacement[2]),
                "drift_x": column(&|p| p.drift[0]),
                "drift_y": column(&|p| p.drift[1]),
                "acceleration_x_m_s2": column(&|p| p.acceleration[0]),
                "acceleration_y_m_s2": column(&|p| p.acceleration[1]),
                "rotational_acceleration_rad_s2": column(&|p| p.acceleration[2]),
                "corner_acceleration_m_s2": column(&|p| p.corner.peak),
                "corner_acceleration_corner": peaks.iter().map(|p| corners[p.corner.peak_corner]).collect::<Vec<_>>(),
                "rms_corner_acceleration_m_s2": column(&|p| p.corner.rms),
            },
            "timings_s": {"setup": setup_seconds, "storm": run_seconds},
        });
        return Ok(serde_json::to_string_pretty(&value).expect("plain JSON"));
    }
    let mut out = format!(
        "{} storm of {} s at Δt = {} s, {order_name}-order, wind towards {}° from x, wake loads from {loads}, seed {}\n",
        study.name, study.storm.duration, study.storm.time_step, run.direction, args.seed
    );
    if let Some(measured) = records_direction {
        out += &format!("  the records measured towards {measured}° (the nearest to the storm's direction)\n");
    }
    for (name, value) in &inputs {
        out += &format!("  {name:<15} {value}\n");
    }
    let milli_g = |a: f64| a / STANDARD_GRAVITY * 1e3;
    let largest = |f: &dyn Fn(&FloorPeaks) -> f64| -> (usize, f64) {
        peaks.iter().enumerate().fold((0, 0.0), |best, (j, p)| if f(p) > best.1 { (j + 1, f(p)) } else { best })
    };
    out += "largest peaks up the height (every floor's in --json):\n";
    let rows: [(&str, Column, &str, bool); 10] = [
        ("displacement along x", &|p| p.displacement[0], "m", false),
        ("displacement along y", &|p| p.displacement[1], "m", false),
        ("rotation", &|p| p.displacement[2], "rad", false),
        ("drift ratio along x", &|p| p.drift[0], "", false),
        ("drift ratio along y", &|p| p.drift[1], "", false),
        ("acceleration along x", &|p| p.acceleration[0], "m/s²", true),
        ("acceleration along y", &|p| p.acceleration[1], "m/s²", true),
        ("rotational acceleration", &|p| p.acceleration[2], "rad/s²", false),
        ("corner acceleration (resultant)", &|p| p.corner.peak, "m/s²", true),
        ("RMS corner acceleration", &|p| p.corner.rms, "m/s²", true),
    ];
    for (name, f, unit, acceleration) in rows {
        let (floor, value) = largest(f);
        out += &format!("  {name:<32} floor {floor:>2}  {value:.5} {unit}");
        if acceleration {
            out += &format!(" ({:.2} milli-g)", milli_g(value));
        }
        out += "\n";
    }
    let roof = &peaks[peaks.len() - 1];
    let corner = corners[roof.corner.peak_corner];
    out += &format!(
        "roof's worst corner: ({}, {}) m from the plan's centre, peak {:.2} milli-g, RMS {:.2} milli-g\n",
        corner[0],
        corner[1],
        milli_g(roof.corner.peak),
        milli_g(roof.corner.rms)
    );
    if let Some(path) = &args.out {
        out += &format!("histories written to {}\n", path.display());
    }
    out += &format!("time: setup {setup_seconds:.3} s, storm {run_seconds:.3} s\n");
    Ok(out)
}

/// The responses whose histories `--out` writes: each `--history` kind (displacement by default)
/// along x, y and in twist (drift along x and y; corner_acceleration at the worst corner) at each
/// of `--history-floors` (the roof by default).
fn history_responses(args: &SimulateArgs, study: &SpatialStudy) -> Result<Vec<SpatialResponse>> {
    let kinds = if args.histories.is_empty() {
        vec![SpatialKind::Displacement]
    } else {
        args.histories.iter().map(|k| SpatialKind::parse(k)).collect::<Result<_>>()?
    };
    if let Some(rms) = kinds.iter().find(|k| k.is_rms()) {
        return Err(Error::invalid(
            "history",
            format!("{} is one value per storm (in the run's peaks); its history is the peak's kind", rms.name()),
        ));
    }
    let floors = match history_floors(args)? {
        HistoryFloors::Roof => vec![study.structure.floors()],
        HistoryFloors::All => (1..=study.structure.floors()).collect(),
        HistoryFloors::These(floors) => floors,
    };
    let mut responses = Vec::new();
    for kind in kinds {
        let directions: &[Option<Dof>] = match kind {
            _ if kind.at_corners() => &[None],
            SpatialKind::Drift => &[Some(Dof::X), Some(Dof::Y)],
            _ => &[Some(Dof::X), Some(Dof::Y), Some(Dof::Rotation)],
        };
        for &floor in &floors {
            for &direction in directions {
                responses.push(SpatialResponse::located(kind, Some(floor), direction, &study.structure)?);
            }
        }
    }
    Ok(responses)
}

/// Writes the histories of `responses` in `run` as CSV, a column each (kind, floor, direction, unit).
fn write_spatial_histories(
    path: &std::path::Path,
    responses: &[SpatialResponse],
    run: &SpatialRun,
    study: &SpatialStudy,
) -> Result<()> {
    let histories = responses.iter().map(|r| r.history(run, &study.structure)).collect::<Result<Vec<Vec<f64>>>>()?;
    let columns: Vec<String> = responses.iter().map(SpatialResponse::column).collect();
    write_histories(path, &columns, &histories, study.storm.time_step)
}
