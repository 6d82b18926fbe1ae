//! The refinement of a structure's coefficients on the simulation error (Eq. 11): the sum of
//! squared free-run errors over a record, minimised by Levenberg-Marquardt on forward
//! sensitivities of the recursion or by the paper's Nelder-Mead simplex.

use super::identify::{Record, simulate};
use super::narx::{DamperTerm, NarxTerm, diverged, rest_output};
use crate::error::Result;
use crate::optimise::{Minimum, NormalEquations, Stop, levenberg_marquardt, nelder_mead};
use crate::progress::Observer;
use faer::{ColRef, MatRef};
use serde::{Deserialize, Serialize};

/// How the coefficients are refined on the simulation error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Refinement {
    /// Levenberg-Marquardt with forward sensitivities of the recursion.
    LevenbergMarquardt,
    /// The paper's Nelder-Mead simplex.
    NelderMead,
    /// Keep the one-step-ahead least-squares coefficients.
    None,
}

/// How one experiment's refinement ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct RefinementOutcome {
    /// Why the optimiser stopped.
    pub stop: Stop,
    /// Iterations it took.
    pub iterations: usize,
}

/// How the refinements of one mode's experiments ended: how many stopped for each reason, and
/// their iterations (all zero when the coefficients are not refined).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct RefinementSummary {
    /// Met the optimiser's tolerance.
    pub converged: usize,
    /// Stopped at the iteration cap: the coefficients may be short of the optimum.
    pub iteration_cap: usize,
    /// Levenberg-Marquardt found no improving step at its largest damping: an optimum to the
    /// precision of the free run.
    pub no_improving_step: usize,
    /// The one-step fit's free run diverged, so the refinement could not start from it.
    pub undefined_start: usize,
    /// Median iterations over the experiments.
    pub median_iterations: f64,
    /// Most iterations of any experiment.
    pub max_iterations: usize,
}

impl RefinementSummary {
    /// Counts how the refinements of one mode's experiments ended.
    pub fn of(outcomes: &[RefinementOutcome]) -> Self {
        let mut summary = RefinementSummary::default();
        for outcome in outcomes {
            *match outcome.stop {
                Stop::Converged => &mut summary.converged,
                Stop::IterationCap => &mut summary.iteration_cap,
                Stop::NoImprovingStep => &mut summary.no_improving_step,
                Stop::UndefinedStart => &mut summary.undefined_start,
            } += 1;
        }
        let mut iterations: Vec<usize> = outcomes.iter().map(|o| o.iterations).collect();
        iterations.sort_unstable();
        summary.max_iterations = iterations.last().copied().unwrap_or(0);
        summary.median_iterations = match iterations.len() {
            0 => 0.0,
            n if n % 2 == 1 => iterations[n / 2] as f64,
            n => (iterations[n / 2 - 1] + iterations[n / 2]) as f64 / 2.0,
        };
        summary
    }
}

/// Refines `theta` on the sum of squared free-run errors over the record; each iteration (one
/// free run of the record) asks the observer whether to stop. Returns the coefficients and, when
/// they were refined, how the refinement ended.
pub fn refine(
    method: Refinement,
    terms: &[NarxTerm],
    theta: Vec<f64>,
    record: &Record,
    damping_floor: f64,
    observer: &dyn Observer,
) -> Result<(Vec<f64>, Option<RefinementOutcome>)> {
    let minimum = match method {
        Refinement::LevenbergMarquardt => {
            let stable = StableCoordinates::of(terms, damping_floor);
            let minimum = levenberg_marquardt(
                stable.coordinates_of(theta),
                |x| stable.normal_equations(x, |theta| normal_equations(terms, theta, record)),
                observer,
            )?;
            Minimum { x: stable.theta_of(&minimum.x), ..minimum }
        }
        Refinement::NelderMead => nelder_mead(theta, |theta| sum_of_squares(terms, theta, record), observer)?,
        Refinement::None => return Ok((theta, None)),
    };
    let Minimum { x, stop, iterations, .. } = minimum;
    Ok((x, Some(RefinementOutcome { stop, iterations })))
}

/// The coordinates Levenberg-Marquardt refines an AR(2) part in: u = ln(1 + a₂ − f) and
/// v = ln(1 − a₁ − a₂) in place of a₁ and a₂, the other coefficients as they are, f the damping
/// floor. Every point of them is a linear part that is stable by itself (1 + a₂ > f > 0 and
/// 1 − a₁ − a₂ > 0, the third condition a₂ − a₁ < 1 holding near a₁ ≈ 2) and damped at least
/// as much as the floor says, whatever the damper terms beside it carry: where the dampers'
/// terms could take all the damping, the one-step fit and the simulation error would as soon
/// let the linear part go unstable and the damper terms hold it, which holds only while the
/// dampers move (a limit cycle where they do not). The expansions are of ln(1 + a₂) and ln s
/// ([`super::parametrization::Parametrization::StableGains`]), so every experiment admits them
/// and every predicted linear part is stable too. A start below the floor (a one-step fit whose
/// damper terms took the damping) is moved just above it. Only structures with a term of the own
/// velocity (its law D(Δy), or [`DamperTerm::Modulated`]), the terms that can take a mode's
/// damping from its linear part, are refined in these coordinates; the others in their
/// coefficients. (With the law alone refined freely, a design covering 18-62 m/s had a mode 1
/// whose linear part was unstable in some experiment: its expansions fell back to plain gains and
/// the free run diverged at 20 m/s.)
/// That term's own coefficient c is refined as w with c = −w²: a damping (or none) at every
/// trial point, so that the expansions of √(−c/s)
/// ([`super::parametrization::Parametrization::DissipativeGains`]) are admitted by every
/// experiment and no prediction turns the term into a source of energy (an expansion of the
/// plain gain crossed zero below the design, and the free run grew).
struct StableCoordinates {
    /// Indices of a₁ and a₂, when the structure has exactly these two autoregressive terms.
    ar2: Option<(usize, usize)>,
    /// Indices of the own-velocity secant terms, refined in w = √(−c).
    dissipative: Vec<usize>,
    /// f, the least 1 + a₂ (positive).
    floor: f64,
}

/// The smallest 1 − a₁ − a₂ a start is moved to: about a hundredth of the stiffness a mode of
/// 1 rad/s has at 100 Hz ((ωΔt)² = 10⁻⁴).
const STIFFNESS_MARGIN: f64 = 1e-6;

impl StableCoordinates {
    fn of(terms: &[NarxTerm], floor: f64) -> StableCoordinates {
        let linear = super::parametrization::linear_outputs(terms);
        let dissipative = super::parametrization::dissipative_terms(terms);
        // Any term of the own velocity (its law, or its secant at another mode's) can take the
        // damping from the linear part.
        let own_velocity = terms.iter().any(|t| t.damper.is_some() && t.reads_own_output());
        let ar2 =
            (own_velocity && linear.len() == 2 && terms[linear[0]].output_lag == 1 && terms[linear[1]].output_lag == 2)
                .then(|| (linear[0], linear[1]));
        StableCoordinates { ar2, dissipative, floor: floor.max(f64::MIN_POSITIVE) }
    }

    fn coordinates_of(&self, mut theta: Vec<f64>) -> Vec<f64> {
        if let Some((i1, i2)) = self.ar2 {
            let (a1, a2) = (theta[i1], theta[i2]);
            theta[i2] = (1.0 + a2 - self.floor).max(0.1 * self.floor).ln();
            theta[i1] = (1.0 - a1 - a2).max(STIFFNESS_MARGIN).ln();
        }
        for &i in &self.dissipative {
            // A one-step fit that made the term a source starts from a tenth of it as a damping
            // (w = 0 would be a stationary point the refinement could not leave).
            theta[i] = (-theta[i]).max(0.1 * theta[i].abs()).sqrt();
        }
        theta
    }

    fn theta_of(&self, x: &[f64]) -> Vec<f64> {
        let mut theta = x.to_vec();
        if let Some((i1, i2)) = self.ar2 {
            let (v, u) = (x[i1], x[i2]);
            theta[i2] = (self.floor - 1.0) + u.exp();
            theta[i1] = 1.0 - v.exp() - theta[i2];
        }
        for &i in &self.dissipative {
            theta[i] = -x[i] * x[i];
        }
        theta
    }

    /// The normal equations in these coordinates: J_x = J_θ·T with T = ∂θ/∂x, identity but for
    /// ∂a₂/∂u = e^u, ∂a₁/∂u = −e^u, ∂a₁/∂v = −e^v and ∂c/∂w = −2w.
    fn normal_equations(
        &self,
        x: &[f64],
        in_theta: impl Fn(&[f64]) -> Option<NormalEquations>,
    ) -> Option<NormalEquations> {
        let theta = self.theta_of(x);
        if theta.iter().any(|c| !c.is_finite()) {
            return None;
        }
        let mut equations = in_theta(&theta)?;
        if self.ar2.is_none() && self.dissipative.is_empty() {
            return Some(equations);
        }
        let n = x.len();
        let ar2 = self.ar2.map(|(i1, i2)| (i1, i2, x[i2].exp(), x[i1].exp()));
        // Columns of T that differ from the identity: column i2 = e^u (e_i2 − e_i1), column
        // i1 = −e^v e_i1, and column i = −2w_i e_i for each dissipative term.
        let transform = |v: &[f64], k: usize| -> f64 {
            match ar2 {
                Some((i1, i2, eu, _)) if k == i2 => return eu * (v[i2] - v[i1]),
                Some((i1, _, _, ev)) if k == i1 => return -ev * v[i1],
                _ => {}
            }
            if self.dissipative.contains(&k) { -2.0 * x[k] * v[k] } else { v[k] }
        };
        let jtr: Vec<f64> = (0..n).map(|k| transform(&equations.jtr, k)).collect();
        // Tᵀ (JᵀJ) T = ((JᵀJ T)ᵀ) T: the rows transformed, transposed, the rows transformed again.
        let rows_transformed =
            |m: &[f64]| -> Vec<f64> { (0..n * n).map(|e| transform(&m[e / n * n..(e / n + 1) * n], e % n)).collect() };
        let half = rows_transformed(&equations.jtj);
        let transposed: Vec<f64> = (0..n * n).map(|e| half[e % n * n + e / n]).collect();
        equations.jtj = rows_transformed(&transposed);
        equations.jtr = jtr;
        Some(equations)
    }
}

fn sum_of_squares(terms: &[NarxTerm], theta: &[f64], record: &Record) -> f64 {
    match simulate(terms, theta, record) {
        Ok(y_hat) => record.y.iter().zip(&y_hat).map(|(a, b)| (a - b).powi(2)).sum(),
        Err(_) => f64::INFINITY,
    }
}

/// Free run with forward sensitivities s_i(t) = ∂ŷ(t)/∂θ_i:
/// s_i(t) = g_i(t) + Σ_k θ_k ∂g_k/∂ŷ(t − l_k) s_i(t − l_k), and at rest
/// s_i = g_i(y*) / (1 − Σ_k θ_k ∂g_k/∂y(y*)) since the rest state y* moves with θ.
/// Returns the normal equations JᵀJ, Jᵀr of r = y − ŷ and the sum of squares, or None on divergence.
fn normal_equations(terms: &[NarxTerm], theta: &[f64], record: &Record) -> Option<NormalEquations> {
    let p = terms.len();
    let n = record.y.len();
    let q_rest = record.q_rest;
    let (slices, rests) = (record.output_slices(), record.output_rests());
    let rest = rest_output(terms, theta, q_rest, &rests, record.y[0]).ok()?;
    let mut y_hat = vec![0.0; n];
    let mut s = vec![0.0; n * p];
    let rest_output_of = |term: &NarxTerm| term.output_mode.map_or(rest, |j| rests[j]);
    // At rest every damper term is zero whatever θ, and so is its slope in the rest output.
    let slope: f64 = terms
        .iter()
        .zip(theta)
        .filter(|(t, _)| t.reads_own_output() && t.damper.is_none())
        .map(|(t, c)| c * t.output_derivative(rest, q_rest))
        .sum();
    let rest_sensitivity: Vec<f64> = terms
        .iter()
        .map(|t| if t.damper.is_some() { 0.0 } else { t.value(rest_output_of(t), q_rest) / (1.0 - slope) })
        .collect();
    let law = record.law.as_deref();
    let lagged = |series: &[f64], t: usize, lag: usize, rest: f64| if lag > t { rest } else { series[t - lag] };
    y_hat[0] = rest;
    s[..p].copy_from_slice(&rest_sensitivity);
    // s(t) = g(t) + Σ_l b_l(t)·s(t − l): each step gathers the slopes b_l of its value in the own
    // output l steps back, then adds the lagged sensitivity rows once per lag (a short loop over
    // the coefficients that vectorises) rather than once per term that reads the output.
    let depth = terms.iter().filter(|t| t.reads_own_output()).map(NarxTerm::reach).max().unwrap_or(0);
    let mut slopes = vec![0.0; depth + 1];
    let mut row = vec![0.0; p];
    for t in 1..n {
        let mut value = 0.0;
        row.fill(0.0);
        slopes.fill(0.0);
        for (k, (term, c)) in terms.iter().zip(theta).enumerate() {
            if let Some(kind) = term.damper {
                let law = law?;
                let lag = term.output_lag;
                let difference =
                    |series: &[f64], rest: f64| lagged(series, t, lag, rest) - lagged(series, t, lag + 1, rest);
                // Δ·S(Δ) of the own velocity is D(Δ): a modulated term of the own mode is its law.
                let (g, dg) = match (kind, term.output_mode) {
                    (_, None) => {
                        let (g, slope) = law.value_and_slope(record.mode, difference(&y_hat, rest));
                        (g, c * slope)
                    }
                    (kind, Some(j)) => {
                        let d = difference(slices[j], rests[j]);
                        let secant =
                            record.secants.get(j).map_or_else(|| law.secant(j, d), |s| lagged(s, t, lag, s[0]));
                        match kind {
                            DamperTerm::Law => (d * secant, 0.0),
                            DamperTerm::Modulated => (difference(&y_hat, rest) * secant, c * secant),
                        }
                    }
                };
                // ∂Δ/∂ŷ(t − l) = 1 and ∂Δ/∂ŷ(t − l − 1) = −1 for the own output.
                if dg != 0.0 {
                    slopes[lag] += dg;
                    slopes[lag + 1] -= dg;
                }
                value += c * g;
                row[k] += g;
                continue;
            }
            let y_lag = match term.output_mode {
                None if term.output_lag > t => rest,
                None => y_hat[t - term.output_lag],
                Some(j) if term.output_lag > t => rests[j],
                Some(j) => slices[j][t - term.output_lag],
            };
            let q_lag = if term.input_lag > t { q_rest } else { record.q[t - term.input_lag] };
            let g = term.value(y_lag, q_lag);
            value += c * g;
            row[k] += g;
            if term.reads_own_output() {
                slopes[term.output_lag] += c * term.output_derivative(y_lag, q_lag);
            }
        }
        // Before t = 0 the run is at rest, whose sensitivities are row 0's.
        for (lag, &slope) in slopes.iter().enumerate().skip(1).filter(|(_, b)| **b != 0.0) {
            let source = t.saturating_sub(lag) * p;
            for (r, ds) in row.iter_mut().zip(&s[source..source + p]) {
                *r = slope.mul_add(*ds, *r);
            }
        }
        if diverged(value) {
            return None;
        }
        y_hat[t] = value;
        s[t * p..(t + 1) * p].copy_from_slice(&row);
    }
    // JᵀJ and Jᵀr as matrix products over the stored sensitivities (the recursion above is
    // sequential; these vectorise).
    let residuals: Vec<f64> = record.y.iter().zip(&y_hat).map(|(y, f)| y - f).collect();
    let jacobian = MatRef::from_row_major_slice(&s, n, p);
    let jtj_matrix = jacobian.transpose() * jacobian;
    let jtr_matrix = jacobian.transpose() * ColRef::from_slice(&residuals);
    let jtj = (0..p * p).map(|k| jtj_matrix[(k / p, k % p)]).collect();
    let jtr = (0..p).map(|i| jtr_matrix[i]).collect();
    let sum_of_squares = residuals.iter().map(|r| r * r).sum();
    Some(NormalEquations { jtj, jtr, sum_of_squares })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;
    use crate::surrogate::identify::simulation_error;
    use crate::surrogate::identify::tests::{arx, record};

    /// From perturbed coefficients both refinements return to the truth on the simulation error.
    #[test]
    fn refinements_recover_the_true_coefficients() {
        let (terms, theta) = arx();
        let data = record(&theta, &terms, 2);
        let start: Vec<f64> = theta.iter().map(|v| v * 1.01).collect();
        assert!(simulation_error(&terms, &start, &data) > 1e-3);
        for method in [Refinement::LevenbergMarquardt, Refinement::NelderMead] {
            let (refined, outcome) = refine(method, &terms, start.clone(), &data, 1e-9, &Silent).unwrap();
            let error = simulation_error(&terms, &refined, &data);
            assert!(error < 1e-8, "{method:?}: error {error}, θ = {refined:?}");
            let outcome = outcome.expect("refined");
            assert!(outcome.stop != Stop::IterationCap && outcome.stop != Stop::UndefinedStart, "{outcome:?}");
            assert!(outcome.iterations > 0);
        }
        assert_eq!(refine(Refinement::None, &terms, start.clone(), &data, 1e-9, &Silent).unwrap(), (start, None));
    }

    /// Mode 2's record of a model with damper terms, mode 1's output a sine and the law's knees
    /// 3·10⁻³ and 4·10⁻³: the output the model itself gives.
    fn damper_record(terms: &[NarxTerm], theta: &[f64]) -> Record {
        use crate::surrogate::DamperLaw;
        use std::sync::Arc;
        let law = Arc::new(DamperLaw { exponent: 0.38, knees: vec![3e-3, 4e-3] });
        let other: Arc<[f64]> = (0..4000).map(|t| (t as f64 * 0.013).sin()).collect();
        let base = record(&[0.0, 0.0, 0.0, 0.0], &arx().0, 4);
        let mut data = Record { mode: 1, law: Some(law.clone()), ..base };
        data.outputs = vec![other.clone(), other];
        data.secants = Record::secants_of(&data.outputs, &law);
        data.y = simulate(terms, theta, &data).unwrap().into();
        data
    }

    /// The sensitivities of damper terms are right: from perturbed coefficients Levenberg-Marquardt
    /// returns to the truth of a model with the own velocity's law and another mode's secant.
    #[test]
    fn refinement_recovers_damper_term_coefficients() {
        use crate::surrogate::narx::DamperTerm;
        let terms = [
            NarxTerm::input(0, 1),
            NarxTerm::output(1, 1, None),
            NarxTerm::output(2, 1, None),
            NarxTerm::damper(DamperTerm::Law, 1, None),
            NarxTerm::damper(DamperTerm::Modulated, 1, Some(0)),
        ];
        let theta = [0.002, 1.98, -0.985, -0.004, -0.003];
        let data = damper_record(&terms, &theta);
        assert!(data.y.iter().any(|v| v.abs() > 0.05));
        let start: Vec<f64> = theta.iter().map(|v| v * 1.002).collect();
        assert!(simulation_error(&terms, &start, &data) > 1e-4);
        let (refined, _) = refine(Refinement::LevenbergMarquardt, &terms, start, &data, 1e-9, &Silent).unwrap();
        let error = simulation_error(&terms, &refined, &data);
        assert!(error < 1e-10, "error {error}, θ = {refined:?}");
    }

    /// A mode's AR(2) part with its input and its own velocity at mode 1's secant.
    fn secant_structure() -> [NarxTerm; 4] {
        use crate::surrogate::narx::DamperTerm;
        [
            NarxTerm::input(0, 1),
            NarxTerm::output(1, 1, None),
            NarxTerm::output(2, 1, None),
            NarxTerm::damper(DamperTerm::Modulated, 1, Some(0)),
        ]
    }

    /// A truth whose linear part is damped less than the floor (1 + a₂ = 0.015, a term of the own
    /// velocity carrying the rest: its secant at mode 1's, or its own law) is refined to the best
    /// model that keeps the floor: every trial point of Levenberg-Marquardt is a stable linear
    /// part, and the result sits at or above the floor; with the floor below the truth's damping
    /// the truth comes back.
    #[test]
    fn the_refined_linear_part_keeps_the_damping_floor() {
        use crate::surrogate::narx::DamperTerm;
        let mut own_law = secant_structure();
        own_law[3] = NarxTerm::damper(DamperTerm::Law, 1, None);
        for terms in [secant_structure(), own_law] {
            let theta = [0.002, 1.98, -0.985, -0.02];
            let data = damper_record(&terms, &theta);
            let start: Vec<f64> = theta.iter().map(|v| v * 1.002).collect();
            let method = Refinement::LevenbergMarquardt;
            let (below, _) = refine(method, &terms, start.clone(), &data, 1e-3, &Silent).unwrap();
            assert!(simulation_error(&terms, &below, &data) < 1e-10, "{}: θ = {below:?}", terms[3]);
            let floor = 0.02;
            let (held, outcome) = refine(method, &terms, start, &data, floor, &Silent).unwrap();
            assert!(1.0 + held[2] >= floor * (1.0 - 1e-12), "{}: 1 + a₂ = {}", terms[3], 1.0 + held[2]);
            assert!(1.0 - held[1] - held[2] > 0.0);
            assert!(outcome.is_some_and(|o| o.stop != Stop::UndefinedStart));
            assert!(simulation_error(&terms, &held, &data).is_finite());
        }
    }

    /// A truth whose secant term gives energy (c > 0, the linear part's damping holding it) is
    /// refined to the best model whose term is a damping or none: every trial point keeps c ≤ 0.
    #[test]
    fn the_refined_secant_term_stays_a_damping() {
        let terms = secant_structure();
        let theta = [0.002, 1.98, -0.985, 2e-4];
        let data = damper_record(&terms, &theta);
        let start: Vec<f64> = theta.iter().map(|v| v * 1.002).collect();
        let (refined, outcome) = refine(Refinement::LevenbergMarquardt, &terms, start, &data, 1e-3, &Silent).unwrap();
        assert!(refined[3] <= 0.0, "θ = {refined:?}");
        assert!(outcome.is_some_and(|o| o.stop != Stop::UndefinedStart));
        assert!(simulation_error(&terms, &refined, &data).is_finite());
    }

    /// The coordinates map back exactly, and a start below the floor, or with a secant term that
    /// gives energy, is moved to a stable and dissipative one.
    #[test]
    fn stable_coordinates_round_trip() {
        use crate::surrogate::narx::DamperTerm;
        let mut terms = arx().0;
        terms.push(NarxTerm::damper(DamperTerm::Modulated, 1, Some(0)));
        let stable = StableCoordinates::of(&terms, 1e-3);
        let linear = super::super::parametrization::linear_outputs(&terms);
        assert!(StableCoordinates::of(&arx().0, 1e-3).ar2.is_none());
        let mut theta = vec![0.0; terms.len()];
        theta[linear[0]] = 1.97;
        theta[linear[1]] = -0.98;
        let back = stable.theta_of(&stable.coordinates_of(theta.clone()));
        for (a, b) in theta.iter().zip(&back) {
            assert!((a - b).abs() < 1e-14, "{theta:?} vs {back:?}");
        }
        theta[linear[1]] = -1.01;
        let modulated = terms.len() - 1;
        theta[modulated] = 2e-3;
        let moved = stable.theta_of(&stable.coordinates_of(theta));
        assert!(1.0 + moved[linear[1]] > 1e-3, "{moved:?}");
        // A secant term that a one-step fit made a source starts as a tenth of it, a damping.
        assert!((moved[modulated] + 2e-4).abs() < 1e-18, "{moved:?}");
    }

    /// The summary counts each stop reason and takes the median and largest iteration counts.
    #[test]
    fn summary_counts_the_stops() {
        let outcome = |stop, iterations| RefinementOutcome { stop, iterations };
        let summary = RefinementSummary::of(&[
            outcome(Stop::Converged, 4),
            outcome(Stop::IterationCap, 200),
            outcome(Stop::Converged, 6),
            outcome(Stop::NoImprovingStep, 9),
        ]);
        assert_eq!((summary.converged, summary.iteration_cap, summary.no_improving_step), (2, 1, 1));
        assert_eq!((summary.undefined_start, summary.median_iterations, summary.max_iterations), (0, 7.5, 200));
        assert_eq!(RefinementSummary::of(&[]), RefinementSummary::default());
    }
}
