//! Across-wind and torsional loads on a tall building: the forces of its wake (vortex shedding and
//! the turbulence it shapes), which the quasi-steady drag of [`super::WindLoads`] does not hold,
//! and which most often govern a tall building's accelerations.
//!
//! At one wind direction they are given as a high-frequency force-balance test reports them: for
//! the across-wind base moment and the base torque, an RMS coefficient and a normalised spectrum
//! f·S(f)/σ² against the reduced frequency n = f·B/U_H, and the coherence of the two ([`WakeLoads`]);
//! by default from the published model of rectangular prisms ([`published`]), or from the user's
//! wind-tunnel data ([`TunnelData`], format in `docs/wind-tunnel-data.md`). [`WakeField`] spreads
//! them over the floors as one stationary process that [`super::simulate`] realises.
//! Their means are taken as zero (a prism with the wind normal to a face). The user's synchronous
//! floor force records ([`FloorRecords`]) are the other way in: the whole load, drag and mean lift
//! and torque included, scaled from the model to each storm.

mod field;
mod normalised;
pub mod published;
mod records;
#[cfg(test)]
mod tests;
mod tunnel;

pub use field::{WakeField, WakeGeometry};
pub use normalised::{Coherence, NormalisedSpectrum, SpectrumTable};
pub use published::{AcrossWindModel, TorsionModel};
pub use records::{FloorRecords, RECORDS_FORMAT};
pub use tunnel::TunnelData;

use crate::error::{Error, Result};
use serde::Deserialize;

/// What a force-balance spectra file may say of itself in its `format` field.
pub const SPECTRA_FORMAT: &str = "force_balance_spectra";

/// The side ratios D/B the published model holds for.
pub const PUBLISHED_SIDE_RATIOS: (f64, f64) = (0.2, 5.0);

/// The vertical coherence decay k of γ(Δz) = exp(−k |Δz|/B) when none is given: the wake's forces
/// on a prism in turbulent flow stay correlated over about two breadths up the height. Not from a
/// source that could be read here; it does not change the base loads' spectra, only how the load
/// is shared among the modes (see [`WakeField`]).
pub const DEFAULT_VERTICAL_COHERENCE_DECAY: f64 = 0.5;

/// The across-wind and torsional base loads at one wind direction.
#[derive(Debug, Clone, PartialEq)]
pub struct WakeLoads {
    /// C'_L = σ_M/(q_H B H²) of the across-wind base moment.
    pub across_coefficient: f64,
    /// Its normalised spectrum.
    pub across: NormalisedSpectrum,
    /// C'_T = σ_T/(q_H B² H) of the base torque.
    pub torsion_coefficient: f64,
    /// Its normalised spectrum.
    pub torsion: NormalisedSpectrum,
    /// The coherence of the across-wind loads and the torques.
    pub coherence: Coherence,
    /// k of the vertical coherence exp(−k |Δz|/B).
    pub vertical_coherence_decay: f64,
}

impl WakeLoads {
    /// The published model for a prism of side ratio r = D/B (D along the wind, B facing it),
    /// its across-wind loads and torques taken as uncorrelated (the model gives no coherence).
    pub fn published(side_ratio: f64) -> Result<Self> {
        let (low, high) = PUBLISHED_SIDE_RATIOS;
        if !(side_ratio.is_finite() && (low..=high).contains(&side_ratio)) {
            return Err(Error::invalid(
                "aerodynamics.side_ratio",
                format!("the published model holds for side ratios D/B in [{low}, {high}], got {side_ratio}"),
            ));
        }
        Ok(WakeLoads {
            across_coefficient: AcrossWindModel::rms_coefficient(side_ratio),
            across: NormalisedSpectrum::AcrossWind(AcrossWindModel::new(side_ratio)),
            torsion_coefficient: TorsionModel::rms_coefficient(side_ratio),
            torsion: NormalisedSpectrum::Torsion(TorsionModel::new(side_ratio)),
            coherence: Coherence::Constant(0.0),
            vertical_coherence_decay: DEFAULT_VERTICAL_COHERENCE_DECAY,
        })
    }
}

/// Where a building's wake loads come from.
#[derive(Debug, Clone, PartialEq)]
pub enum Aerodynamics {
    /// The published model, at the side ratio of the plan's face nearest normal to the wind.
    Published,
    /// The user's force-balance spectra.
    Tunnel(TunnelData),
    /// The user's synchronous floor force records: the whole load, drag included.
    Records(FloorRecords),
}

/// The `format` a wind-tunnel file names (force-balance spectra when it names none).
#[derive(Deserialize)]
struct FormatProbe {
    #[serde(default)]
    format: Option<String>,
}

impl Aerodynamics {
    /// The wind-tunnel file's data, by the `format` it names: `force_balance_spectra` (the
    /// default) or [`RECORDS_FORMAT`]. Errors name the field at fault.
    pub fn from_json(text: &str) -> Result<Self> {
        let probe: FormatProbe = serde_json::from_str(text)
            .map_err(|e| Error::invalid("aerodynamics", format!("not a wind-tunnel data file: {e}")))?;
        match probe.format.as_deref() {
            None | Some(SPECTRA_FORMAT) => Ok(Aerodynamics::Tunnel(TunnelData::from_json(text)?)),
            Some(RECORDS_FORMAT) => Ok(Aerodynamics::Records(FloorRecords::from_json(text)?)),
            Some(other) => Err(Error::invalid(
                "format",
                format!("must be \"{SPECTRA_FORMAT}\" or \"{RECORDS_FORMAT}\", got \"{other}\""),
            )),
        }
    }

    /// How answers name the source of the loads: `published`, `wind_tunnel` (force-balance
    /// spectra) or `floor_force_records`.
    pub fn name(&self) -> &'static str {
        match self {
            Aerodynamics::Published => "published",
            Aerodynamics::Tunnel(_) => "wind_tunnel",
            Aerodynamics::Records(_) => RECORDS_FORMAT,
        }
    }

    /// The same for a sentence: "the published model", …
    pub fn describe(&self) -> &'static str {
        match self {
            Aerodynamics::Published => "the published model",
            Aerodynamics::Tunnel(_) => "wind-tunnel spectra",
            Aerodynamics::Records(_) => "wind-tunnel floor force records",
        }
    }

    /// The wake loads for wind blowing towards `direction_deg` (counter-clockwise from the plan's
    /// x axis) on a plan of `breadth` along x and `depth` along y, and the breadth B facing the
    /// wind their coefficients and reduced frequencies are taken with.
    pub fn at(&self, direction_deg: f64, breadth: f64, depth: f64) -> Result<(WakeLoads, f64)> {
        match self {
            Aerodynamics::Published => {
                // The face nearest normal to the wind: along x the wind faces the depth.
                let along_x = direction_deg.to_radians().cos().abs() >= direction_deg.to_radians().sin().abs();
                let (facing, along) = if along_x { (depth, breadth) } else { (breadth, depth) };
                Ok((WakeLoads::published(along / facing)?, facing))
            }
            Aerodynamics::Tunnel(data) => Ok((data.at(direction_deg)?, data.reference_breadth_m)),
            Aerodynamics::Records(_) => Err(Error::invalid(
                "wind-tunnel",
                "floor force records are the loads themselves; they give no spectra to simulate from",
            )),
        }
    }
}
