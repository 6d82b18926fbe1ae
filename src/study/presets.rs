//! The built-in studies: the paper's 40-storey frame with its dampers, under two unit readings.

use super::StudySpec;
use crate::error::{Error, Result};
use crate::structure::{Structure, frame40};

/// The built-in studies: the paper's frame with damper coefficients as printed (N·s/m) and the same
/// numbers in kN·s/m, where the dampers really act.
pub const PRESETS: [&str; 2] = ["frame40", "frame40-kn"];
/// The built-in three-dimensional buildings ([`super::SpatialStudy`]): `windmeta modes`,
/// `simulate` and `sample-peaks` take them; the metamodel's commands do not yet.
pub const SPATIAL_PRESETS: [&str; 1] = ["frame40-3d"];
/// The study a calibration request without a preset or a structure calibrates.
pub const DEFAULT_PRESET: &str = "frame40-kn";

/// The study's name, its structure and the scale of its damper coefficients' default range
/// (1 for N·s/m as printed, 1000 for kN·s/m), from the spec's preset and custom structure.
pub(super) fn resolve(spec: &StudySpec) -> Result<(String, Structure, f64)> {
    if spec.spatial_structure.is_some() {
        return Err(Error::invalid(
            "spatial_structure",
            "a three-dimensional building: `windmeta modes`, `simulate` and `sample-peaks` take it, calibrations \
             and the metamodel's answers do not yet",
        ));
    }
    let (name, damper_scale) = match spec.preset.as_deref() {
        Some("frame40") => ("frame40", 1.0),
        Some("frame40-kn") => ("frame40-kn", 1000.0),
        Some(spatial) if SPATIAL_PRESETS.contains(&spatial) => {
            return Err(Error::invalid(
                "preset",
                format!(
                    "`{spatial}` is a three-dimensional building: `windmeta modes`, `simulate` and `sample-peaks` \
                     take it, this command does not yet (it takes {})",
                    PRESETS.join(", ")
                ),
            ));
        }
        Some(other) => {
            return Err(Error::invalid(
                "preset",
                format!("unknown preset `{other}`; the presets are {}", PRESETS.join(", ")),
            ));
        }
        None if spec.structure.is_some() => ("custom", 1.0),
        None => return Err(Error::invalid("preset", "give a preset name or a custom structure")),
    };
    let (structure, name) = match &spec.structure {
        Some(custom) => {
            (custom.build()?, if spec.preset.is_some() { format!("{name}+custom") } else { "custom".into() })
        }
        None => (frame40()?, name.to_string()),
    };
    Ok((name, structure, damper_scale))
}
