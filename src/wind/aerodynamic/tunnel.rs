//! The user's wind-tunnel data: high-frequency force-balance results per wind direction, the RMS
//! coefficients and normalised spectra of the across-wind base moment and the base torque and their
//! coherence, read from the JSON format of `docs/wind-tunnel-data.md`. Between two measured
//! directions every coefficient, spectrum value and coherence is interpolated linearly in the
//! angle (around the circle: 350° and 10° are 20° apart).

use super::{Coherence, DEFAULT_VERTICAL_COHERENCE_DECAY, NormalisedSpectrum, SpectrumTable, WakeLoads};
use crate::error::{Error, Result};
use serde::Deserialize;

/// Force-balance results of one building.
#[derive(Debug, Clone, PartialEq)]
pub struct TunnelData {
    /// The breadth B (m, full scale) the coefficients and reduced frequencies are taken with.
    pub reference_breadth_m: f64,
    /// k of the vertical coherence exp(−k |Δz|/B).
    pub vertical_coherence_decay: f64,
    /// The measured directions, increasing in [0°, 360°), with their loads.
    directions: Vec<(f64, WakeLoads)>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TunnelFile {
    /// Checked by [`super::Aerodynamics::from_json`].
    #[serde(default)]
    #[allow(dead_code)]
    format: Option<String>,
    reference_breadth_m: f64,
    #[serde(default)]
    vertical_coherence_decay: Option<f64>,
    directions: Vec<DirectionFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DirectionFile {
    wind_direction_deg: f64,
    across_wind: ComponentFile,
    torsion: ComponentFile,
    #[serde(default)]
    coherence: Option<CoherenceFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ComponentFile {
    rms_coefficient: f64,
    reduced_frequencies: Vec<f64>,
    spectrum: Vec<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum CoherenceFile {
    Constant(f64),
    Table { reduced_frequencies: Vec<f64>, values: Vec<f64> },
}

/// At most this many directions (every degree) and points per spectrum: a file is read whole.
const MAX_DIRECTIONS: usize = 360;
const MAX_POINTS: usize = 100_000;

impl TunnelData {
    /// Reads the JSON text of a data file; errors name the field at fault.
    pub fn from_json(text: &str) -> Result<Self> {
        let file: TunnelFile = serde_json::from_str(text)
            .map_err(|e| Error::invalid("aerodynamics.tunnel", format!("not a wind-tunnel data file: {e}")))?;
        let breadth = file.reference_breadth_m;
        if !(breadth.is_finite() && breadth > 0.0) {
            return Err(Error::invalid("reference_breadth_m", format!("must be positive, got {breadth}")));
        }
        let decay = file.vertical_coherence_decay.unwrap_or(DEFAULT_VERTICAL_COHERENCE_DECAY);
        if !(decay.is_finite() && decay >= 0.0) {
            return Err(Error::invalid("vertical_coherence_decay", format!("must be finite and ≥ 0, got {decay}")));
        }
        if file.directions.is_empty() || file.directions.len() > MAX_DIRECTIONS {
            return Err(Error::invalid(
                "directions",
                format!("needs between 1 and {MAX_DIRECTIONS} directions, got {}", file.directions.len()),
            ));
        }
        let mut directions = file
            .directions
            .into_iter()
            .enumerate()
            .map(|(k, d)| Ok((check_direction(k, d.wind_direction_deg)?, loads_of(k, d, decay)?)))
            .collect::<Result<Vec<_>>>()?;
        directions.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(pair) = directions.windows(2).find(|pair| pair[0].0 == pair[1].0) {
            return Err(Error::invalid("directions", format!("{}° is given twice", pair[0].0)));
        }
        Ok(TunnelData { reference_breadth_m: breadth, vertical_coherence_decay: decay, directions })
    }

    /// The measured directions (degrees).
    pub fn directions(&self) -> Vec<f64> {
        self.directions.iter().map(|d| d.0).collect()
    }

    /// The loads at `direction_deg`, interpolated between the two measured directions around it.
    pub fn at(&self, direction_deg: f64) -> Result<WakeLoads> {
        if !direction_deg.is_finite() {
            return Err(Error::invalid("inputs.wind_direction", format!("must be finite, got {direction_deg}")));
        }
        let angle = direction_deg.rem_euclid(360.0);
        let count = self.directions.len();
        if count == 1 {
            return Ok(self.directions[0].1.clone());
        }
        // The measured direction at or before the angle, around the circle, and the next.
        let after = self.directions.partition_point(|d| d.0 <= angle);
        let (before, next) = ((after + count - 1) % count, after % count);
        let (from, to) = (self.directions[before].0, self.directions[next].0);
        let span = (to - from).rem_euclid(360.0);
        let t = if span == 0.0 { 0.0 } else { (angle - from).rem_euclid(360.0) / span };
        Ok(blend(&self.directions[before].1, &self.directions[next].1, t))
    }
}

fn check_direction(k: usize, degrees: f64) -> Result<f64> {
    if degrees.is_finite() && (0.0..360.0).contains(&degrees) {
        Ok(degrees)
    } else {
        Err(Error::invalid(
            format!("directions[{k}].wind_direction_deg"),
            format!("must lie in [0, 360), got {degrees}"),
        ))
    }
}

fn loads_of(k: usize, d: DirectionFile, decay: f64) -> Result<WakeLoads> {
    let component = |name: &str, c: ComponentFile| -> Result<(f64, NormalisedSpectrum)> {
        let field = format!("directions[{k}].{name}");
        if !(c.rms_coefficient.is_finite() && c.rms_coefficient >= 0.0) {
            return Err(Error::invalid(
                format!("{field}.rms_coefficient"),
                format!("must be finite and ≥ 0, got {}", c.rms_coefficient),
            ));
        }
        if c.reduced_frequencies.len() > MAX_POINTS {
            return Err(Error::invalid(format!("{field}.reduced_frequencies"), format!("at most {MAX_POINTS} points")));
        }
        let table = SpectrumTable::new(&field, c.reduced_frequencies, c.spectrum)?;
        Ok((c.rms_coefficient, NormalisedSpectrum::Table(table)))
    };
    let (across_coefficient, across) = component("across_wind", d.across_wind)?;
    let (torsion_coefficient, torsion) = component("torsion", d.torsion)?;
    let field = format!("directions[{k}].coherence");
    let coherence = match d.coherence {
        None => Coherence::Constant(0.0),
        Some(CoherenceFile::Constant(value)) => Coherence::constant(&field, value)?,
        Some(CoherenceFile::Table { reduced_frequencies, values }) => {
            if reduced_frequencies.len() > MAX_POINTS {
                return Err(Error::invalid(
                    format!("{field}.reduced_frequencies"),
                    format!("at most {MAX_POINTS} points"),
                ));
            }
            Coherence::table(&field, reduced_frequencies, values)?
        }
    };
    Ok(WakeLoads {
        across_coefficient,
        across,
        torsion_coefficient,
        torsion,
        coherence,
        vertical_coherence_decay: decay,
    })
}

/// (1 − t)·a + t·b of every coefficient, and of the spectra and coherences on the union of their
/// reduced frequencies.
fn blend(a: &WakeLoads, b: &WakeLoads, t: f64) -> WakeLoads {
    if t == 0.0 {
        return a.clone();
    }
    let mix = |x: f64, y: f64| (1.0 - t) * x + t * y;
    let spectrum = |x: &NormalisedSpectrum, y: &NormalisedSpectrum| {
        let grid = union(abscissae_of_spectrum(x), abscissae_of_spectrum(y));
        let values = grid.iter().map(|&n| mix(x.value(n), y.value(n))).collect();
        NormalisedSpectrum::Table(SpectrumTable::from_parts(grid, values))
    };
    let coherence = match (&a.coherence, &b.coherence) {
        (Coherence::Constant(x), Coherence::Constant(y)) => Coherence::Constant(mix(*x, *y)),
        (x, y) => {
            let grid = union(abscissae_of_coherence(x), abscissae_of_coherence(y));
            let values = grid.iter().map(|&n| mix(x.value(n), y.value(n))).collect();
            Coherence::Table { reduced_frequencies: grid, values }
        }
    };
    WakeLoads {
        across_coefficient: mix(a.across_coefficient, b.across_coefficient),
        across: spectrum(&a.across, &b.across),
        torsion_coefficient: mix(a.torsion_coefficient, b.torsion_coefficient),
        torsion: spectrum(&a.torsion, &b.torsion),
        coherence,
        vertical_coherence_decay: a.vertical_coherence_decay,
    }
}

fn abscissae_of_spectrum(spectrum: &NormalisedSpectrum) -> &[f64] {
    match spectrum {
        NormalisedSpectrum::Table(table) => table.reduced_frequencies(),
        _ => &[],
    }
}

fn abscissae_of_coherence(coherence: &Coherence) -> &[f64] {
    match coherence {
        Coherence::Table { reduced_frequencies, .. } => reduced_frequencies,
        Coherence::Constant(_) => &[],
    }
}

/// The sorted union of two increasing sequences, without repeats.
fn union(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut all: Vec<f64> = a.iter().chain(b).copied().collect();
    all.sort_by(f64::total_cmp);
    all.dedup();
    all
}
