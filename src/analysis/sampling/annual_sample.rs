//! One stratified sample of a climate's storms, read as several columns of peaks at once: the
//! floors of a serviceability check, or the values of a swept input. Every column comes from the
//! same storms (the same inputs, speeds and phases), so that the columns' levels differ by what
//! distinguishes the columns and not by sampling noise; and every column shares one allocation of
//! storms to the strata, chosen from the pilot for all the columns' aims together.

use super::draws::{DivergedStorm, name_diverged};
use super::strata::{StormRows, StratifiedPeaks, WindStrata, pilot};
use crate::error::Result;
use crate::uncertainty::Rng;

/// One in this many of an analysis's storms go to its pilot, equally over the strata.
pub const PILOT_SHARE: usize = 4;

/// The storms of an annual sample: how their inputs are drawn, how many, and where the metamodel
/// was calibrated.
pub struct AnnualDesign<'a> {
    /// How the storms' inputs are drawn.
    pub rows: StormRows<'a>,
    /// Storms in all, pilot included.
    pub samples: usize,
    /// The calibration's lowest and highest wind speeds (m/s).
    pub calibrated: [f64; 2],
}

/// A level one column's allocation aims at: (column, level).
pub type Aim = (usize, f64);

/// Every column's stratified peaks, from the same storms.
pub struct AnnualSample {
    /// Each column's peaks, by stratum.
    pub columns: Vec<StratifiedPeaks>,
    /// Storms run (each through every column).
    pub storms: usize,
    /// Storms whose free run diverged in some column (infinite peaks there, exceeding every level).
    pub diverged: usize,
    /// The first few diverged storms with their inputs.
    pub first_diverged: Vec<DivergedStorm>,
}

impl AnnualDesign<'_> {
    /// Runs the pilot (a quarter of the storms, equally over the strata), then the rest by
    /// Neyman's allocation for the levels `aims` picks from the pilot's columns.
    /// `peaks_of(rows, first)` answers `[row][column]` for rows drawn in turn (`first`: the rows
    /// run before, so that every row gets its own storm).
    pub fn draw(
        &self,
        rng: &mut Rng,
        mut peaks_of: impl FnMut(&[Vec<f64>], usize) -> Result<Vec<Vec<f64>>>,
        aims: impl FnOnce(&[StratifiedPeaks]) -> Vec<Aim>,
    ) -> Result<AnnualSample> {
        let strata: &WindStrata = self.rows.strata;
        let (mut storms, mut diverged, mut first_diverged) = (0, 0, Vec::new());
        let mut stage = |counts: &[usize]| -> Result<(Vec<Vec<f64>>, Vec<bool>)> {
            let (rows, speeds) = self.rows.rows(counts, rng)?;
            let peaks = peaks_of(&rows, storms)?;
            let any_infinite: Vec<f64> =
                peaks.iter().map(|row| if row.iter().any(|p| p.is_infinite()) { f64::INFINITY } else { 0.0 }).collect();
            diverged += any_infinite.iter().filter(|p| p.is_infinite()).count();
            name_diverged(self.rows.inputs, &rows, storms.., &any_infinite, &mut first_diverged);
            storms += rows.len();
            let outside = speeds.iter().map(|v| !(self.calibrated[0]..=self.calibrated[1]).contains(v)).collect();
            Ok((peaks, outside))
        };
        let pilot_counts = pilot(strata, self.samples, PILOT_SHARE, "samples")?;
        let (peaks, outside) = stage(&pilot_counts)?;
        let width = peaks.first().map_or(0, Vec::len);
        let column = |peaks: &[Vec<f64>], c: usize| -> Vec<f64> { peaks.iter().map(|row| row[c]).collect() };
        let mut columns: Vec<StratifiedPeaks> =
            (0..width).map(|c| StratifiedPeaks::new(strata, &pilot_counts, &column(&peaks, c), &outside)).collect();
        let budget = self.samples - pilot_counts.iter().sum::<usize>();
        if strata.count() > 1 && budget > 0 {
            let aims = aims(&columns);
            let aimed: Vec<(&StratifiedPeaks, f64)> = aims.iter().map(|&(c, level)| (&columns[c], level)).collect();
            let counts = strata.neyman(&aimed, budget);
            let (peaks, outside) = stage(&counts)?;
            for (c, stratified) in columns.iter_mut().enumerate() {
                stratified.add(&counts, &column(&peaks, c), &outside);
            }
        }
        Ok(AnnualSample { columns, storms, diverged, first_diverged })
    }
}
