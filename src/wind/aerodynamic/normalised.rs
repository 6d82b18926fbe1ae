//! Normalised spectra of a building's aerodynamic base loads, F(n) = f·S(f)/σ² against the
//! reduced frequency n = f·B/U_H (B the breadth facing the wind, U_H the mean speed at the roof),
//! as force-balance tests report them, and the coherence of two loads against the same n.

use super::published::{AcrossWindModel, TorsionModel};
use crate::error::{Error, Result};

/// The reduced frequencies over which a spectrum's area is taken: six decades about the
/// shedding frequency (n ≈ 0.1), far beyond where any published or measured spectrum holds energy.
const AREA_RANGE: (f64, f64) = (1e-4, 1e2);
/// Simpson intervals per decade of that range.
const AREA_INTERVALS_PER_DECADE: usize = 2000;

/// f·S(f)/σ² against the reduced frequency, from a table or a published model.
#[derive(Debug, Clone, PartialEq)]
pub enum NormalisedSpectrum {
    /// Measured values, interpolated.
    Table(SpectrumTable),
    /// The published across-wind model of rectangular prisms.
    AcrossWind(AcrossWindModel),
    /// The published torsional model of rectangular prisms.
    Torsion(TorsionModel),
}

impl NormalisedSpectrum {
    /// F(n) at the reduced frequency n = f·B/U_H.
    pub fn value(&self, reduced_frequency: f64) -> f64 {
        match self {
            NormalisedSpectrum::Table(table) => table.value(reduced_frequency),
            NormalisedSpectrum::AcrossWind(model) => model.value(reduced_frequency),
            NormalisedSpectrum::Torsion(model) => model.value(reduced_frequency),
        }
    }

    /// ∫ F(n) d(ln n): 1 for an exactly normalised spectrum; a measured or fitted one comes close.
    /// Loads are simulated with F divided by its area, so that their RMS is the RMS coefficient's.
    pub fn area(&self) -> f64 {
        let (low, high) = (AREA_RANGE.0.ln(), AREA_RANGE.1.ln());
        let intervals = 2 * (AREA_INTERVALS_PER_DECADE * 3); // even, 6 decades
        let h = (high - low) / intervals as f64;
        let f = |k: usize| self.value((low + k as f64 * h).exp());
        let inner: f64 = (1..intervals).map(|k| if k % 2 == 1 { 4.0 * f(k) } else { 2.0 * f(k) }).sum();
        h / 3.0 * (f(0) + inner + f(intervals))
    }
}

/// A measured spectrum: values at increasing reduced frequencies, interpolated linearly in
/// (ln n, ln F) between two positive values (a power law, as spectra fall off) and linearly where
/// one is zero; zero outside the table.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumTable {
    reduced_frequencies: Vec<f64>,
    values: Vec<f64>,
}

impl SpectrumTable {
    /// A table of `values` (F ≥ 0, not all zero) at `reduced_frequencies` (positive, strictly
    /// increasing), at least two; `field` names it in errors.
    pub fn new(field: &str, reduced_frequencies: Vec<f64>, values: Vec<f64>) -> Result<Self> {
        check_abscissae(field, &reduced_frequencies, values.len())?;
        if let Some((k, v)) = values.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0)) {
            return Err(Error::invalid(format!("{field}.spectrum[{k}]"), format!("must be finite and ≥ 0, got {v}")));
        }
        if values.iter().all(|&v| v == 0.0) {
            return Err(Error::invalid(format!("{field}.spectrum"), "holds no energy: every value is zero"));
        }
        Ok(SpectrumTable { reduced_frequencies, values })
    }

    /// A table of values already checked (a blend of two checked tables).
    pub(super) fn from_parts(reduced_frequencies: Vec<f64>, values: Vec<f64>) -> Self {
        SpectrumTable { reduced_frequencies, values }
    }

    /// The tabulated reduced frequencies.
    pub fn reduced_frequencies(&self) -> &[f64] {
        &self.reduced_frequencies
    }

    /// F at n, interpolated.
    pub fn value(&self, n: f64) -> f64 {
        let Some((k, t)) = bracket(&self.reduced_frequencies, n) else { return 0.0 };
        let (a, b) = (self.values[k], self.values[k + 1]);
        if a > 0.0 && b > 0.0 { (a.ln() + t * (b.ln() - a.ln())).exp() } else { a + t * (b - a) }
    }
}

/// The coherence of the across-wind force and the torque at one reduced frequency (the real part
/// of their normalised cross-spectrum: windmeta simulates the coincident part only).
#[derive(Debug, Clone, PartialEq)]
pub enum Coherence {
    /// The same at every frequency, in [−1, 1].
    Constant(f64),
    /// Values in [−1, 1] at increasing reduced frequencies, linear in ln n, held at the ends.
    Table {
        /// The reduced frequencies n, increasing.
        reduced_frequencies: Vec<f64>,
        /// ρ at each.
        values: Vec<f64>,
    },
}

impl Coherence {
    /// A table of coherences; `field` names it in errors.
    pub fn table(field: &str, reduced_frequencies: Vec<f64>, values: Vec<f64>) -> Result<Self> {
        check_abscissae(field, &reduced_frequencies, values.len())?;
        for (k, &v) in values.iter().enumerate() {
            check_unit(&format!("{field}.values[{k}]"), v)?;
        }
        Ok(Coherence::Table { reduced_frequencies, values })
    }

    /// A constant coherence; `field` names it in errors.
    pub fn constant(field: &str, value: f64) -> Result<Self> {
        check_unit(field, value)?;
        Ok(Coherence::Constant(value))
    }

    /// ρ at n.
    pub fn value(&self, n: f64) -> f64 {
        match self {
            Coherence::Constant(value) => *value,
            Coherence::Table { reduced_frequencies, values } => {
                let clamped = n.clamp(reduced_frequencies[0], reduced_frequencies[reduced_frequencies.len() - 1]);
                let (k, t) = bracket(reduced_frequencies, clamped).unwrap_or((reduced_frequencies.len() - 2, 1.0));
                values[k] + t * (values[k + 1] - values[k])
            }
        }
    }
}

fn check_unit(field: &str, value: f64) -> Result<()> {
    if value.is_finite() && value.abs() <= 1.0 {
        Ok(())
    } else {
        Err(Error::invalid(field, format!("a coherence must lie in [−1, 1], got {value}")))
    }
}

/// At least two positive, finite, strictly increasing reduced frequencies, as many as `values`.
fn check_abscissae(field: &str, reduced_frequencies: &[f64], values: usize) -> Result<()> {
    if reduced_frequencies.len() < 2 || reduced_frequencies.len() != values {
        return Err(Error::invalid(
            format!("{field}.reduced_frequencies"),
            format!("needs at least two points and one value each, got {} and {values}", reduced_frequencies.len()),
        ));
    }
    for (k, pair) in reduced_frequencies.windows(2).enumerate() {
        if !(pair[0].is_finite() && pair[0] > 0.0 && pair[1].is_finite() && pair[1] > pair[0]) {
            return Err(Error::invalid(
                format!("{field}.reduced_frequencies[{}]", k + 1),
                format!("must be positive, finite and increasing, got {} after {}", pair[1], pair[0]),
            ));
        }
    }
    Ok(())
}

/// The interval k with x_k ≤ n ≤ x_{k+1} and the fraction of it in ln n; `None` outside.
fn bracket(abscissae: &[f64], n: f64) -> Option<(usize, f64)> {
    let last = abscissae.len() - 1;
    if !(n >= abscissae[0] && n <= abscissae[last]) {
        return None;
    }
    let k = abscissae.partition_point(|&x| x <= n).clamp(1, last) - 1;
    let t = (n / abscissae[k]).ln() / (abscissae[k + 1] / abscissae[k]).ln();
    Some((k, t))
}
