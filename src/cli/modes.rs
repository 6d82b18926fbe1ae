//! `windmeta modes`: frequencies, periods, generalized masses and roof-normalised shapes.

use super::StudyArgs;
use crate::error::Result;
use clap::Args;
use serde_json::json;

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
