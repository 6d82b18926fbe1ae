//! `windmeta modes`: frequencies, periods, generalized masses and roof-normalised shapes; for a
//! three-dimensional building also each mode's shares of sway in x, sway in y and twist.

use super::StudyArgs;
use crate::error::Result;
use crate::structure::spatial::Dof;
use crate::study::ECCENTRICITY_INPUTS;
use clap::Args;
use serde_json::json;
use std::f64::consts::PI;

/// The study whose modes `windmeta modes` prints, and in which form.
#[derive(Debug, Clone, Args)]
pub struct ModesArgs {
    /// The study whose modes are printed.
    #[command(flatten)]
    pub study: StudyArgs,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `windmeta modes`: a table of the modes, or JSON with `--json`.
pub fn modes(args: &ModesArgs) -> Result<String> {
    if args.study.is_spatial() {
        return spatial_modes(args);
    }
    let study = args.study.study()?;
    let modes = &study.modes;
    let shapes: Vec<Vec<f64>> =
        (0..modes.count()).map(|m| (0..study.structure.floors()).map(|j| modes.shapes[(j, m)]).collect()).collect();
    if args.json {
        let value = json!({
            "preset": study.name,
            "frequencies_rad_s": modes.frequencies,
            "periods_s": modes.periods(),
            "modal_masses_kg": modes.modal_masses,
            "shapes": shapes,
        });
        return Ok(serde_json::to_string_pretty(&value).expect("plain JSON"));
    }
    let mut out = format!(
        "{}: {} floors, roof at {:.1} m\n",
        study.name,
        study.structure.floors(),
        study.structure.floor_elevations.last().unwrap()
    );
    out += "mode  ω (rad/s)  f (Hz)   T (s)   M_m (kg)\n";
    for (m, (w, mass)) in modes.frequencies.iter().zip(&modes.modal_masses).enumerate() {
        out += &format!(
            "{:>4}  {:>9.4}  {:>6.4}  {:>6.3}  {:>10.4e}\n",
            m + 1,
            w,
            w / (2.0 * std::f64::consts::PI),
            2.0 * std::f64::consts::PI / w,
            mass
        );
    }
    out += "shapes (roof = 1), floor by floor from the roof down:\n";
    for j in (0..study.structure.floors()).rev() {
        let row: Vec<String> = shapes.iter().map(|s| format!("{:>8.4}", s[j])).collect();
        out += &format!("{:>5}  {}\n", j + 1, row.join(" "));
    }
    Ok(out)
}

/// The retained modes of a three-dimensional study (up to its three degrees of freedom per floor),
/// its centres of mass where the eccentricity inputs' means put them (`--fix eccentricity_y=2.44`).
fn spatial_modes(args: &ModesArgs) -> Result<String> {
    let study = args.study.spatial_study()?;
    let (building, modes) = (&study.structure, &study.modes);
    let eccentricity = ECCENTRICITY_INPUTS.map(|name| study.inputs.marginal(name).map_or(0.0, |m| m.mean()));
    let name = &study.name;
    let floors = building.floors();
    let component = |m: usize, d: Dof| -> Vec<f64> { (0..floors).map(|j| modes.at(m, j, d)).collect() };
    if args.json {
        let shapes: Vec<_> = (0..modes.count())
            .map(|m| json!({"x_m": component(m, Dof::X), "y_m": component(m, Dof::Y), "rotation_rad": component(m, Dof::Rotation)}))
            .collect();
        let shares: Vec<_> = modes.shares.iter().map(|s| json!({"x": s[0], "y": s[1], "rotation": s[2]})).collect();
        let value = json!({
            "preset": name,
            "eccentricity_m": eccentricity,
            "frequencies_rad_s": modes.frequencies,
            "periods_s": modes.frequencies.iter().map(|w| 2.0 * PI / w).collect::<Vec<_>>(),
            "modal_masses_kg": modes.modal_masses,
            "shares": shares,
            "shapes": shapes,
        });
        return Ok(serde_json::to_string_pretty(&value).expect("plain JSON"));
    }
    let plan = building.plans[floors - 1];
    let mut out = format!(
        "{name}: {floors} floors of {} m × {} m, roof at {:.1} m, centre of mass at ({}, {}) m from the plan's centre\n",
        plan.breadth,
        plan.depth,
        building.floor_elevations[floors - 1],
        eccentricity[0],
        eccentricity[1]
    );
    out += "mode  ω (rad/s)  f (Hz)   T (s)   M_m (kg)    x      y      twist   roof (x, y, r·θ)\n";
    let radius = plan.radius_of_gyration();
    for m in 0..modes.count() {
        let w = modes.frequencies[m];
        let [x, y, twist] = modes.shares[m];
        let roof = [
            modes.at(m, floors - 1, Dof::X),
            modes.at(m, floors - 1, Dof::Y),
            radius * modes.at(m, floors - 1, Dof::Rotation),
        ];
        out += &format!(
            "{:>4}  {:>9.4}  {:>6.4}  {:>6.3}  {:>10.4e}  {:>5.3}  {:>5.3}  {:>5.3}   ({:>6.3}, {:>6.3}, {:>6.3})\n",
            m + 1,
            w,
            w / (2.0 * PI),
            2.0 * PI / w,
            modes.modal_masses[m],
            x,
            y,
            twist,
            roof[0],
            roof[1],
            roof[2]
        );
    }
    out += "shares: each mode's parts of φᵀMφ in sway along x, along y and in twist; shapes with --json\n";
    Ok(out)
}
