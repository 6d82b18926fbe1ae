//! Certified annual curves: the stratified metamodel estimate ([`crate::analysis::sampling::strata`]) corrected
//! stratum by stratum by storms run through both the reference model and the metamodel, and the
//! corrections combined by total probability:
//!
//!   P̂(x) = Σ_s w_s [k_s/n_s + (1/N_s) Σ_{N_s} (I_H − I_L)] + q_min.
//!
//! A stratum's correction is a difference of paired proportions with Bonett & Price's band
//! ([`super::certify`]), whose pseudo-counts give it a width even where no pair disagrees, and
//! the correction's own variance is w_s²·q_s/N_s however rare x: at 10⁻³ a year the commonest
//! stratum (w = 0.5) with a dozen pairs would add ±0.03. But there a mismatch needs one of the
//! stratum's rare storms whose metamodel peak lies within the models' disagreement of x, and the
//! stratum's thousands of metamodel storms say how rare: with ε = ln(peak_H/peak_L) distributed as
//! the pairs' errors (pooled over the strata), the predicted mismatch rate is
//!
//!   ρ_s(x) = (1/n_s) Σ_{i ∈ s} P(L_i·e^ε and L_i on different sides of x).
//!
//! A stratum where no pair disagreed about x and 3·w_s·ρ_s(x) is narrower than its correction's
//! band is left uncorrected, and 3·w_s·ρ_s(x) is added to the band as a bound on what it might have
//! corrected. The factor three is what the certification assumes: that no stratum's mismatches
//! outnumber the pooled errors' prediction threefold. A diverged metamodel storm (counted as
//! exceeding) is a mismatch at worst: its share of the stratum is added to the bound as it is.
//!
//! The reference storms go half to a pilot, equally over the strata, and the rest by Neyman's
//! allocation on the mismatch: N_s ∝ w_s·√q̃_s (the difference's variance is about q_s/N_s), q̃_s the
//! larger of the observed and the predicted rate, summed over the return levels asked for each
//! weighted by 1/P(x)², as the metamodel's storms are.

use super::certify::{AdjustedDifference, Certification, CertifyOptions};
use crate::analysis::sampling::reference_storms::PairedPeak;
use crate::analysis::sampling::strata::{Estimate, StormRows, StratifiedPeaks, pilot};
use crate::error::Result;
use crate::study::Order;
use crate::uncertainty::rng_from_seed;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

/// How many times the pooled errors' predicted mismatch rate a stratum left uncorrected is taken
/// to have at most.
const PREDICTION_SAFETY: f64 = 3.0;

/// What the reference storms did to an annual curve: threshold by threshold (the metamodel's own
/// annual probabilities and band, the mismatch rate and the correction, each combined over the
/// strata by their probabilities), and how they were spread.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct HazardCertification {
    /// The annual curve's certification threshold by threshold, each figure combined over the strata.
    #[serde(flatten)]
    pub points: Certification,
    /// Per threshold: the part of the band's half-width that bounds the strata left uncorrected,
    /// Σ 3·w_s·ρ_s(x) over them (ρ_s the mismatch rate the pairs' pooled errors predict there).
    pub uncorrected_bound: Vec<f64>,
    /// Reference storms in each wind stratum, from the commonest speeds to the rarest.
    pub reference_storms_per_stratum: Vec<usize>,
}

/// The storms run through both models, by wind stratum.
pub struct PairedStrata {
    strata: Vec<Vec<PairedPeak>>,
    order: Order,
    /// The pairs' ln(peak_H/peak_L), ascending (a pair whose metamodel diverged has none: it
    /// shows as a mismatch in its own stratum).
    errors: Vec<f64>,
}

/// A certified annual probability and what made it.
pub struct CertifiedPoint {
    /// The certified estimate with its band.
    pub estimate: Estimate,
    /// The metamodel's own estimate.
    pub metamodel: Estimate,
    /// The rate at which the two models disagree about x, combined over the strata.
    pub mismatch_rate: f64,
    /// What the pairs added to the metamodel's probability.
    pub correction: f64,
    /// The lower end of the correction's band.
    pub correction_lower: f64,
    /// The upper end of the correction's band.
    pub correction_upper: f64,
    /// The bound on what the strata left uncorrected might have corrected, added to the band.
    pub uncorrected_bound: f64,
}

impl PairedStrata {
    /// The reference storms of a certified curve: one in `pilot_share` a pilot over the strata,
    /// the rest by Neyman's allocation on the mismatch at the `targets` ([`Self::allocation`]),
    /// drawn like the metamodel's storms from their own `seed`; `pairs_of(rows, first)` runs them
    /// through both models.
    pub fn draw(
        draws: &StormRows,
        metamodel: &StratifiedPeaks,
        targets: &[f64],
        certify: &CertifyOptions,
        pilot_share: usize,
        seed: u64,
        mut pairs_of: impl FnMut(&[Vec<f64>], usize) -> Result<Vec<PairedPeak>>,
    ) -> Result<Self> {
        let mut rng = rng_from_seed(seed);
        let storms = certify.reference_storms;
        let pilot_counts = pilot(draws.strata, storms, pilot_share, "certify.reference_storms")?;
        let (rows, _) = draws.rows(&pilot_counts, &mut rng)?;
        let mut paired = PairedStrata::new(&pilot_counts, &pairs_of(&rows, 0)?, certify.order);
        let budget = storms - rows.len();
        if draws.strata.count() > 1 && budget > 0 {
            let counts = paired.allocation(metamodel, targets, budget);
            let (more, _) = draws.rows(&counts, &mut rng)?;
            paired.add(&counts, &pairs_of(&more, rows.len())?);
        }
        Ok(paired)
    }

    /// `pairs` in the order of the strata, `counts[s]` of them in stratum s.
    pub fn new(counts: &[usize], pairs: &[PairedPeak], order: Order) -> Self {
        let mut paired = PairedStrata { strata: vec![Vec::new(); counts.len()], order, errors: Vec::new() };
        paired.add(counts, pairs);
        paired
    }

    /// More pairs, in the order of the strata.
    pub fn add(&mut self, counts: &[usize], pairs: &[PairedPeak]) {
        let mut first = 0;
        for (stratum, &count) in self.strata.iter_mut().zip(counts) {
            stratum.extend_from_slice(&pairs[first..first + count]);
            first += count;
        }
        self.errors = self.strata.iter().flatten().filter_map(log_error).collect();
        self.errors.sort_by(f64::total_cmp);
    }

    /// The levels a certified curve's return levels are sought among: the metamodel's finite peaks
    /// and the pairs' (a certified level may lie beyond the metamodel's peaks, among the
    /// reference's), ascending.
    pub fn levels_with(&self, metamodel: &StratifiedPeaks) -> Vec<f64> {
        let mut levels = metamodel.finite_peaks();
        levels.extend(self.finite_peaks());
        levels.sort_by(f64::total_cmp);
        levels
    }

    /// Every finite peak of the pairs, the reference's and the metamodel's.
    pub fn finite_peaks(&self) -> impl Iterator<Item = f64> + '_ {
        self.strata.iter().flatten().flat_map(|p| [p.reference, p.metamodel]).filter(|p| p.is_finite())
    }

    /// Stratum `s`'s pairs where only the reference exceeds x, and where only the metamodel does.
    fn mismatches(&self, s: usize, x: f64) -> (f64, f64) {
        self.strata[s].iter().fold((0.0, 0.0), |(h, l), p| match (p.reference > x, p.metamodel > x) {
            (true, false) => (h + 1.0, l),
            (false, true) => (h, l + 1.0),
            _ => (h, l),
        })
    }

    /// ρ_s(x): the mismatch rate at x that the pairs' pooled errors predict for stratum `s`'s
    /// metamodel storms, and the share of them that diverged (each a mismatch, at worst); none
    /// where the pairs give no errors.
    fn predicted_mismatch(&self, s: usize, metamodel: &StratifiedPeaks, x: f64) -> Option<(f64, f64)> {
        let errors = &self.errors;
        let (&least, &most) = (errors.first()?, errors.last()?);
        let n = errors.len() as f64;
        let (lo, hi) = (x * (-most.max(0.0)).exp(), x * (-least.min(0.0)).exp());
        let (window, diverged, storms) = metamodel.window(s, lo, hi);
        let crossing: f64 = window
            .iter()
            .map(|&(peak, _)| {
                let below = errors.partition_point(|&e| e <= (x / peak).ln()) as f64 / n;
                if peak <= x { 1.0 - below } else { below }
            })
            .sum();
        Some((crossing / storms as f64, diverged as f64 / storms as f64))
    }

    /// What leaving stratum `s` uncorrected at x may cost: w_s·(3·ρ_s + its diverged share).
    fn uncorrected_bound(&self, s: usize, metamodel: &StratifiedPeaks, x: f64) -> Option<f64> {
        let (predicted, diverged) = self.predicted_mismatch(s, metamodel, x)?;
        Some(metamodel.weights()[s] * (PREDICTION_SAFETY * predicted + diverged))
    }

    /// Neyman's allocation of `budget` more pairs on the mismatch at the `targets`: n_s ∝
    /// w_s·√q̃_s/P(x) summed over them, q̃_s the larger of the observed and the predicted rate
    /// (the observed one where none is predicted); equal shares when every q̃_s is 0.
    pub fn allocation(&self, metamodel: &StratifiedPeaks, targets: &[f64], budget: usize) -> Vec<usize> {
        let weights = metamodel.weights();
        let mut scores = vec![0.0; self.strata.len()];
        for &x in targets {
            let total = metamodel.exceedance_fraction(x).max(f64::MIN_POSITIVE);
            for (s, score) in scores.iter_mut().enumerate() {
                let (h, l) = self.mismatches(s, x);
                let observed = (h + l + 0.5) / (self.strata[s].len() as f64 + 1.0);
                let q = self
                    .predicted_mismatch(s, metamodel, x)
                    .map_or(observed, |(p, diverged)| (p + diverged).max((h + l) / self.strata[s].len() as f64));
                *score += weights[s] * q.sqrt() / total;
            }
        }
        let sum: f64 = scores.iter().sum();
        if sum > 0.0 {
            scores.iter().map(|a| (budget as f64 * a / sum).floor() as usize).collect()
        } else {
            vec![budget / self.strata.len(); self.strata.len()]
        }
    }

    /// P(peak_H > x): the metamodel's stratified estimate plus each corrected stratum's mean
    /// I_H − I_L, weighted by its probability. The band: the metamodel part's (centre and variance
    /// of its Wilson band) and each corrected stratum's Bonett-Price difference, variances summed,
    /// widened by the bound on the strata left uncorrected.
    pub fn exceedance(&self, metamodel: &StratifiedPeaks, x: f64, confidence: f64) -> CertifiedPoint {
        let z = Normal::standard().inverse_cdf(0.5 + confidence / 2.0);
        let (mut mismatch_rate, mut correction, mut centre, mut band_variance, mut variance, mut bound) =
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for (s, (w, pairs)) in metamodel.weights().iter().zip(&self.strata).enumerate() {
            let n = pairs.len() as f64;
            let (h, l) = self.mismatches(s, x);
            mismatch_rate += w * (h + l) / n;
            let adjusted = AdjustedDifference::bonett_price(h, l, n);
            match self.uncorrected_bound(s, metamodel, x) {
                Some(uncorrected) if h + l == 0.0 && uncorrected < z * w * adjusted.variance.sqrt() => {
                    bound += uncorrected;
                }
                _ => {
                    let (d, q) = ((h - l) / n, (h + l) / n);
                    correction += w * d;
                    variance += w * w * (q - d * d) / n;
                    centre += w * adjusted.centre;
                    band_variance += w * w * adjusted.variance;
                }
            }
        }
        let part = metamodel.sampled(x, confidence);
        let part_band_variance = ((part.upper - part.lower) / (2.0 * z)).powi(2);
        let half_width = z * (part_band_variance + band_variance).sqrt() + bound;
        let band_centre = (part.lower + part.upper) / 2.0 + centre;
        let unsampled = metamodel.unsampled();
        let sampled = (part.probability + correction).clamp(0.0, 1.0);
        let probability = (sampled + unsampled).min(1.0);
        let correction_half_width = z * band_variance.sqrt() + bound;
        CertifiedPoint {
            estimate: Estimate {
                probability,
                lower: (band_centre - half_width).clamp(0.0, 1.0),
                upper: ((band_centre + half_width).clamp(0.0, 1.0) + unsampled).min(1.0),
                cov: (sampled > 0.0).then(|| (part.variance + variance).sqrt() / probability),
                beyond: part.beyond + unsampled,
            },
            metamodel: metamodel.exceedance(x, confidence),
            mismatch_rate,
            correction,
            correction_lower: (centre - correction_half_width).max(-1.0),
            correction_upper: (centre + correction_half_width).min(1.0),
            uncorrected_bound: bound,
        }
    }

    /// The certification of the curve whose points at its thresholds are `points`.
    pub fn certification(&self, points: &[CertifiedPoint]) -> HazardCertification {
        let column = |f: fn(&CertifiedPoint) -> f64| points.iter().map(f).collect();
        HazardCertification {
            points: Certification {
                reference_storms: self.strata.iter().map(Vec::len).sum(),
                order: self.order,
                metamodel_probabilities: column(|p| p.metamodel.probability),
                metamodel_lower: column(|p| p.metamodel.lower),
                metamodel_upper: column(|p| p.metamodel.upper),
                mismatch_rate: column(|p| p.mismatch_rate),
                correction: column(|p| p.correction),
                correction_lower: column(|p| p.correction_lower),
                correction_upper: column(|p| p.correction_upper),
            },
            uncorrected_bound: column(|p| p.uncorrected_bound),
            reference_storms_per_stratum: self.strata.iter().map(Vec::len).collect(),
        }
    }
}

/// ln(peak_H/peak_L), 0 where both are 0; none where the metamodel diverged or only one is 0.
fn log_error(pair: &PairedPeak) -> Option<f64> {
    if pair.reference > 0.0 && pair.metamodel > 0.0 && pair.metamodel.is_finite() {
        Some((pair.reference / pair.metamodel).ln())
    } else {
        (pair.reference == pair.metamodel).then_some(0.0)
    }
}
