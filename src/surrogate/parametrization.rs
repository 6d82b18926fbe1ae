//! The coefficients a metamodel expands in polynomial chaos, as an invertible map of the NARX
//! coefficients.
//!
//! At 100 Hz a lightly damped mode has autoregressive coefficients a₁ ≈ 2, a₂ ≈ −1 whose sum is
//! pinned down by the data to 10⁻⁸ while each alone scatters from storm to storm by 10⁻⁵ along a
//! valley of equal simulation error. Expanded separately, with different sparse bases, their sum —
//! and with it the static gain b/(1 − a₁ − a₂) — loses the digits that matter. Terms of one kind at
//! neighbouring lags are nearly collinear at 100 Hz in the same way. So the expansions are of
//! s = 1 − Σ a_j (in place of the first autoregressive coefficient), the other autoregressive
//! coefficients as they are, every other coefficient divided by s (gains, which the data fix well),
//! and for every group of terms of one kind at several lags (Q(t), Q(t−2); y(t−1)², y(t−2)²) the
//! group's total gain in place of its first member. The map is exactly invertible.

use super::narx::{DamperTerm, NarxTerm};
use serde::{Deserialize, Serialize};

/// How NARX coefficients map to the expanded ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Parametrization {
    /// The NARX coefficients themselves (the paper's choice).
    Direct,
    /// s = 1 − Σ a_j, the remaining autoregressive coefficients, and gains θ_i / s.
    Gains,
    /// As `Gains`, with ln s in place of s and ln(1 + a_n) in place of the autoregressive
    /// coefficient of the longest lag. For an AR(2) part, s > 0 and 1 + a₂ > 0 are its stability
    /// conditions (the third, a₂ − a₁ < 1, holds near a₂ ≈ −1), so every prediction is stable.
    StableGains,
    /// As `StableGains`, an AR(2) part expanded as logit(s/2) and logit(1 + a₂) (stable at any
    /// value), and √(−θ/s) in place of the gain of every own velocity at another
    /// mode's secant (Δy·S(y_j), a damping that follows another mode's motion), mapped back as
    /// θ = −s·φ²: every predicted term of that kind is dissipative or zero, so the expansions
    /// cannot turn a damper into a source of energy at inputs between or beyond the
    /// experiments. A square root, not a logarithm, because an experiment may need none of the
    /// term (θ = 0), where a logarithm is unbounded.
    DissipativeGains,
}

/// ln(p / (1 − p)).
fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

/// 1 / (1 + e^(−x)), the inverse of [`logit`].
fn logistic(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// The own velocity at another mode's secant, whose coefficient is a damping (negative).
pub(super) fn dissipative_terms(terms: &[NarxTerm]) -> Vec<usize> {
    (0..terms.len()).filter(|&i| terms[i].damper == Some(DamperTerm::Modulated)).collect()
}

/// The mode's own autoregressive terms c·y(t − l), by lag.
pub(super) fn linear_outputs(terms: &[NarxTerm]) -> Vec<usize> {
    let mut idx: Vec<usize> =
        (0..terms.len()).filter(|&i| terms[i].reads_own_output() && terms[i].is_linear_output()).collect();
    idx.sort_by_key(|&i| terms[i].output_lag);
    idx
}

/// Groups of two or more terms of the same kind (the same powers) at different lags, other than the
/// autoregressive ones, each sorted by lag: nearly collinear at 100 Hz, so each group's sum is what
/// the data fix.
fn lag_groups(terms: &[NarxTerm]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, t) in terms.iter().enumerate() {
        if t.is_constant() || (t.reads_own_output() && t.is_linear_output()) {
            continue;
        }
        let kind = |t: &NarxTerm| (t.output_power, t.input_power, t.output_mode, t.damper);
        match groups.iter_mut().find(|g| kind(&terms[g[0]]) == kind(t)) {
            Some(g) => g.push(i),
            None => groups.push(vec![i]),
        }
    }
    groups.retain(|g| g.len() > 1);
    for g in &mut groups {
        g.sort_by_key(|&i| (terms[i].output_lag, terms[i].input_lag));
    }
    groups
}

impl Parametrization {
    /// The best available for a structure and the coefficients of its experiments: dissipative
    /// gains when the structure has own-velocity secant terms and every experiment admits their
    /// logarithms and the linear part's, stable gains when every experiment admits the linear
    /// part's, else gains, else the coefficients themselves.
    pub fn choose(terms: &[NarxTerm], experiments: &[Vec<f64>]) -> Parametrization {
        let linear = linear_outputs(terms);
        if linear.is_empty() {
            return Parametrization::Direct;
        }
        let admits_logs = experiments.iter().all(|theta| {
            let s = 1.0 - linear.iter().map(|&i| theta[i]).sum::<f64>();
            s > 0.0 && (linear.len() < 2 || 1.0 + theta[*linear.last().unwrap()] > 0.0)
        });
        let dissipative = dissipative_terms(terms);
        let within_triangle = |theta: &[f64]| {
            linear.len() != 2 || {
                let (a1, a2) = (theta[linear[0]], theta[linear[1]]);
                let s = 1.0 - a1 - a2;
                s < 2.0 && -1.0 < a2 && a2 < 0.0
            }
        };
        let admits_dissipative = !dissipative.is_empty()
            && experiments.iter().all(|theta| {
                within_triangle(theta) && dissipative.iter().all(|&i| theta[i] <= 0.0 && theta[i].is_finite())
            });
        match (admits_logs, admits_dissipative) {
            (true, true) => Parametrization::DissipativeGains,
            (true, false) => Parametrization::StableGains,
            (false, _) => Parametrization::Gains,
        }
    }

    /// Whether the linear part is expanded as ln s and ln(1 + a_n).
    fn takes_stable_logs(self) -> bool {
        matches!(self, Parametrization::StableGains | Parametrization::DissipativeGains)
    }

    /// The indices of s and a₂ when the linear part is an AR(2) expanded within the whole of its
    /// stability triangle (dissipative gains): logit(s/2) and logit(1 + a₂), so that every
    /// prediction has 0 < s < 2 and −1 < a₂ < 0, which with a₁ = 1 − s − a₂ satisfies all three
    /// conditions (a₂ > −1, a₁ + a₂ < 1, a₂ − a₁ < 1) however far an expansion strays. The
    /// logarithms alone bound only two: continued below a small design, mode 3's ln(1 + a₂)
    /// grew to 1 + a₂ = 1.3·10⁴ at 12 m/s and the free run diverged in three steps.
    fn bounded_ar2(self, linear: &[usize]) -> Option<(usize, usize)> {
        (self == Parametrization::DissipativeGains && linear.len() == 2).then(|| (linear[0], linear[1]))
    }

    /// NARX coefficients → expanded coefficients.
    pub fn forward(self, terms: &[NarxTerm], theta: &[f64]) -> Vec<f64> {
        let linear = linear_outputs(terms);
        if self == Parametrization::Direct || linear.is_empty() {
            return theta.to_vec();
        }
        let s = 1.0 - linear.iter().map(|&i| theta[i]).sum::<f64>();
        let groups = lag_groups(terms);
        let mut phi: Vec<f64> = (0..theta.len())
            .map(|i| {
                if i == linear[0] {
                    s
                } else if linear.contains(&i) {
                    theta[i]
                } else {
                    theta[i] / s
                }
            })
            .collect();
        for group in &groups {
            phi[group[0]] = group.iter().map(|&i| theta[i]).sum::<f64>() / s;
        }
        if let Some((first, last)) = self.bounded_ar2(&linear) {
            phi[first] = logit(s / 2.0);
            phi[last] = logit(1.0 + theta[last]);
        } else if self.takes_stable_logs() {
            phi[linear[0]] = s.ln();
            if linear.len() >= 2 {
                let last = *linear.last().unwrap();
                phi[last] = (1.0 + theta[last]).ln();
            }
        }
        if self == Parametrization::DissipativeGains {
            for i in dissipative_terms(terms) {
                phi[i] = (-phi[i]).max(0.0).sqrt();
            }
        }
        phi
    }

    /// Expanded coefficients → NARX coefficients.
    pub fn inverse(self, terms: &[NarxTerm], phi: &[f64]) -> Vec<f64> {
        let linear = linear_outputs(terms);
        if self == Parametrization::Direct || linear.is_empty() {
            return phi.to_vec();
        }
        let mut phi = phi.to_vec();
        if self == Parametrization::DissipativeGains {
            for i in dissipative_terms(terms) {
                phi[i] = -phi[i] * phi[i];
            }
        }
        if let Some((first, last)) = self.bounded_ar2(&linear) {
            phi[first] = 2.0 * logistic(phi[first]);
            phi[last] = logistic(phi[last]) - 1.0;
        } else if self.takes_stable_logs() {
            phi[linear[0]] = phi[linear[0]].exp();
            if linear.len() >= 2 {
                let last = *linear.last().unwrap();
                phi[last] = phi[last].exp() - 1.0;
            }
        }
        let s = phi[linear[0]];
        let others: f64 = linear[1..].iter().map(|&i| phi[i]).sum();
        let groups = lag_groups(terms);
        let mut theta: Vec<f64> = (0..phi.len())
            .map(|i| {
                if i == linear[0] {
                    1.0 - s - others
                } else if linear.contains(&i) {
                    phi[i]
                } else {
                    phi[i] * s
                }
            })
            .collect();
        for group in &groups {
            theta[group[0]] = s * (phi[group[0]] - group[1..].iter().map(|&i| phi[i]).sum::<f64>());
        }
        theta
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surrogate::narx::NarxOptions;

    #[test]
    fn gains_round_trip() {
        let d = NarxOptions { cross_terms: true, ..Default::default() }.dictionary(1, 3, false);
        let theta: Vec<f64> =
            (0..d.len()).map(|i| 0.01 * (i as f64 + 1.0) * if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
        for p in [Parametrization::Gains, Parametrization::StableGains, Parametrization::Direct] {
            let back = p.inverse(&d, &p.forward(&d, &theta));
            for (a, b) in theta.iter().zip(&back) {
                assert!((a - b).abs() < 1e-14, "{p:?}: {theta:?} vs {back:?}");
            }
        }
        assert_eq!(Parametrization::choose(&d, std::slice::from_ref(&theta)), Parametrization::StableGains);
        // A structure without autoregressive terms expands the coefficients directly.
        let static_terms = [NarxTerm::CONSTANT, d[1]];
        assert_eq!(Parametrization::choose(&static_terms, &[vec![1.0, 2.0]]), Parametrization::Direct);
    }

    /// With own-velocity secant terms whose coefficients are negative or zero in every
    /// experiment, the expansions are of their square roots: the map round-trips, and any
    /// expanded value (however far a polynomial strays) comes back as a damping.
    #[test]
    fn dissipative_gains_keep_the_sign() {
        let options = NarxOptions { secant_terms: true, coupling_lags: 1, ..Default::default() };
        let d = options.dictionary(1, 3, true);
        let dissipative = dissipative_terms(&d);
        assert_eq!(dissipative.len(), 2, "{d:?}");
        let linear = linear_outputs(&d);
        let mut theta: Vec<f64> = (0..d.len()).map(|i| 1e-3 * (i as f64 + 1.0)).collect();
        theta[linear[0]] = 1.99;
        theta[linear[1]] = -0.995;
        for &i in &dissipative {
            theta[i] = -2e-4 * (i as f64);
        }
        theta[dissipative[1]] = 0.0;
        let p = Parametrization::choose(&d, std::slice::from_ref(&theta));
        assert_eq!(p, Parametrization::DissipativeGains);
        let back = p.inverse(&d, &p.forward(&d, &theta));
        for (a, b) in theta.iter().zip(&back) {
            assert!((a - b).abs() < 1e-14 * a.abs().max(1.0), "{theta:?} vs {back:?}");
        }
        let mut strayed = p.forward(&d, &theta);
        for &i in &dissipative {
            strayed[i] -= 40.0;
        }
        assert!(dissipative.iter().all(|&i| p.inverse(&d, &strayed)[i] < 0.0));
        // However far the linear part's expansions stray, it stays inside the stability triangle
        // (on its edge to rounding where the logistic saturates, 40 away).
        let tolerance = 1e-12;
        for (ds, da2) in [(40.0, 40.0), (-40.0, 40.0), (40.0, -40.0), (9.0, 9.0), (-9.0, -9.0)] {
            let mut far = p.forward(&d, &theta);
            far[linear[0]] += ds;
            far[linear[1]] += da2;
            let back = p.inverse(&d, &far);
            let (a1, a2) = (back[linear[0]], back[linear[1]]);
            let inside = a2 > -1.0 - tolerance && a1 + a2 < 1.0 + tolerance && a2 - a1 < 1.0 + tolerance;
            assert!(inside, "a₁ = {a1}, a₂ = {a2}");
        }
        // One experiment with a positive coefficient keeps the plain stable gains.
        let mut positive = theta.clone();
        positive[dissipative[0]] = 1e-5;
        assert_eq!(Parametrization::choose(&d, &[theta, positive]), Parametrization::StableGains);
    }
}
