//! NARX models of one modal coordinate (Eqs. 6-7 and 18): the candidate terms, their evaluation on
//! measured (one-step-ahead) or simulated (free-run) outputs, and the free run itself.
//!
//! Series are scaled to O(1) by per-mode constants before they reach a model. Before t = 0 the
//! structure is at rest under the mean load: the output history is the model's own fixed point under
//! the mean input, which is what the reference's static start means for the metamodel.

use super::damper_law::DamperLaw;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt;

/// One candidate term y(t − output_lag)^output_power · Q(t − input_lag)^input_power (Eq. 18); all
/// powers zero is the constant. With `output_mode` set, the output factor is another mode's
/// displacement: the dampers couple the modes, which a single-input model cannot see.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct NarxTerm {
    /// Lag of the output factor (steps).
    pub output_lag: usize,
    /// Power of the output factor; 0 leaves it out.
    pub output_power: u32,
    /// Lag of the input factor (steps).
    pub input_lag: usize,
    /// Power of the input factor; 0 leaves it out.
    pub input_power: u32,
    /// Another mode (0-based) whose output the term reads; `None` is the mode's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_mode: Option<usize>,
    /// A term of the dampers' law of a velocity (see [`DamperTerm`]) instead of a power
    /// (`output_power` 1, `input_power` 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damper: Option<DamperTerm>,
}

/// The terms of the dampers' law (`DamperLaw`) a model may read, of the first differences
/// Δ_s = y_s(t − l) − y_s(t − l − 1) (velocities times Δt) of the term's mode s.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum DamperTerm {
    /// D(Δ_s): the law of mode s's velocity, the force its motion alone makes in the dampers.
    Law,
    /// Δ·S(Δ_s), S(Δ) = D(Δ)/Δ: the mode's own velocity damped at the law's secant at another
    /// mode's velocity. Where mode s (the first, in a building) dominates the dampers' velocities,
    /// the force's part from this mode's own motion is c·|v_s|^(α−1)·v, which no law of the own
    /// velocity gives (mode 2's peak roof acceleration, fitted to the storm itself: 0.965 of the
    /// reference's without it, 0.999 with it).
    Modulated,
}

impl NarxTerm {
    /// The constant term.
    pub const CONSTANT: NarxTerm =
        NarxTerm { output_lag: 0, output_power: 0, input_lag: 0, input_power: 0, output_mode: None, damper: None };

    /// y(t − lag) of the mode itself or of another one.
    pub fn output(output_lag: usize, output_power: u32, output_mode: Option<usize>) -> NarxTerm {
        NarxTerm { output_lag, output_power, output_mode, ..NarxTerm::CONSTANT }
    }

    /// Q(t − lag)^power.
    pub fn input(input_lag: usize, input_power: u32) -> NarxTerm {
        NarxTerm { input_lag, input_power, ..NarxTerm::CONSTANT }
    }

    /// A damper term at lag `output_lag` of the mode itself or of another one (for
    /// [`DamperTerm::Modulated`], always another).
    pub fn damper(kind: DamperTerm, output_lag: usize, output_mode: Option<usize>) -> NarxTerm {
        NarxTerm { output_lag, output_power: 1, output_mode, damper: Some(kind), ..NarxTerm::CONSTANT }
    }

    /// Whether the term is c·y(t − lag) of some mode, the recursion's linear part.
    pub fn is_linear_output(&self) -> bool {
        self.output_power == 1 && self.input_power == 0 && self.damper.is_none()
    }

    /// The furthest step back the term reads.
    pub fn reach(&self) -> usize {
        self.input_lag.max(self.output_lag + self.damper.is_some() as usize)
    }

    /// Whether the term reads this mode's own output (feedback) rather than only others'.
    pub fn reads_own_output(&self) -> bool {
        self.output_power > 0 && (self.output_mode.is_none() || self.damper == Some(DamperTerm::Modulated))
    }

    /// Whether the term is the constant.
    pub fn is_constant(&self) -> bool {
        self.output_power == 0 && self.input_power == 0
    }

    /// Value given y(t − output_lag) and Q(t − input_lag) (not for a velocity term).
    #[inline]
    pub fn value(&self, y_lagged: f64, q_lagged: f64) -> f64 {
        power(y_lagged, self.output_power) * power(q_lagged, self.input_power)
    }

    /// ∂/∂y(t − output_lag) of the value.
    #[inline]
    pub fn output_derivative(&self, y_lagged: f64, q_lagged: f64) -> f64 {
        if self.output_power == 0 {
            return 0.0;
        }
        self.output_power as f64 * power(y_lagged, self.output_power - 1) * power(q_lagged, self.input_power)
    }
}

#[inline]
fn power(x: f64, p: u32) -> f64 {
    match p {
        0 => 1.0,
        1 => x,
        2 => x * x,
        3 => x * x * x,
        _ => x.powi(p as i32),
    }
}

impl fmt::Display for NarxTerm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_constant() {
            return write!(f, "1");
        }
        let mut parts = Vec::new();
        let exponent = |p: u32| if p > 1 { format!("^{p}") } else { String::new() };
        let name = self.output_mode.map_or("y".to_string(), |j| format!("y{}", j + 1));
        if let Some(kind) = self.damper {
            parts.push(match kind {
                DamperTerm::Law => format!("D({name}(t-{}))", self.output_lag),
                DamperTerm::Modulated => format!("Δy(t-{0})·S({name}(t-{0}))", self.output_lag),
            });
        } else if self.output_power > 0 {
            parts.push(format!("{name}(t-{}){}", self.output_lag, exponent(self.output_power)));
        }
        if self.input_power > 0 {
            let lag = if self.input_lag == 0 { "Q(t)".to_string() } else { format!("Q(t-{})", self.input_lag) };
            parts.push(format!("{lag}{}", exponent(self.input_power)));
        }
        write!(f, "{}", parts.join("·"))
    }
}

/// The full NARX model to select from. The defaults are the paper's: l₁ + l₂ ≤ 3, l₂ ≤ 1,
/// n_y = 1, 2 and n_Q = 0, 1, 2, without cross products: 10 candidates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(default, deny_unknown_fields)]
pub struct NarxOptions {
    /// Largest total degree l₁ + l₂ of a term.
    #[cfg_attr(feature = "openapi", schema(minimum = 1, maximum = 5))]
    #[serde(deserialize_with = "crate::count::count")]
    pub max_degree: u32,
    /// Output lags 1 ..= output_lags.
    #[cfg_attr(feature = "openapi", schema(minimum = 1, maximum = 10))]
    #[serde(deserialize_with = "crate::count::count")]
    pub output_lags: usize,
    /// Input lags 0 ..= input_lags.
    #[cfg_attr(feature = "openapi", schema(minimum = 0, maximum = 10))]
    #[serde(deserialize_with = "crate::count::count")]
    pub input_lags: usize,
    /// Largest power of the input in a term (at most `max_degree`).
    #[cfg_attr(feature = "openapi", schema(minimum = 1, maximum = 5))]
    #[serde(deserialize_with = "crate::count::count")]
    pub max_input_power: u32,
    /// Whether products of an output power and an input power are candidates.
    pub cross_terms: bool,
    /// Most terms in a selected model (the constant included).
    #[cfg_attr(feature = "openapi", schema(minimum = 2, maximum = 30))]
    #[serde(deserialize_with = "crate::count::count")]
    pub max_terms: usize,
    /// Lags 1 ..= coupling_lags of every other retained mode's displacement as candidates (0: each
    /// mode on its own, as in the paper).
    #[cfg_attr(feature = "openapi", schema(minimum = 0, maximum = 10))]
    #[serde(deserialize_with = "crate::count::count")]
    pub coupling_lags: usize,
    /// With dampers whose exponent is not 1: the damper law of the mode's own velocity and, with
    /// coupling, of the other modes' as candidates besides the paper's polynomial dictionary (see
    /// `DamperLaw`). Polynomials cannot express a damping that falls with the amplitude; with the
    /// law among the candidates the peak acceleration's and damper force's errors are about half
    /// the paper dictionary's, within the design's wind speeds and beyond (docs/accuracy.md).
    /// False: the paper's dictionary alone, a 10 000-storm curve in about a third of the time.
    pub damper_terms: bool,
    /// With `damper_terms` and coupling, also each mode's own velocity at the law's secant at
    /// another mode's, Δ_m·S(Δ_s) (`DamperTerm::Modulated`): the force a mode's own motion
    /// makes in dampers whose velocity is mostly another mode's. Every experiment's linear part
    /// is refined in stable coordinates that keep half the structure's own damping and the
    /// term's coefficient as a damping, and it is expanded as one, so no prediction is unstable
    /// or a source of energy. At full size it takes the peak roof acceleration's mean bias on
    /// frame40-kn from 3 % to under 1 % (docs/method.md).
    pub secant_terms: bool,
}

/// Most terms a selected NARX model may have: every term is a coefficient with its own polynomial
/// chaos expansion, and the free run's cost grows with them; the paper's models have at most 10.
pub const MAX_NARX_TERMS: usize = 30;

impl Default for NarxOptions {
    fn default() -> Self {
        NarxOptions {
            max_degree: 3,
            output_lags: 2,
            input_lags: 2,
            max_input_power: 1,
            cross_terms: false,
            max_terms: 10,
            coupling_lags: 2,
            damper_terms: true,
            secant_terms: true,
        }
    }
}

impl NarxOptions {
    /// Refuses options outside their bounds, naming the field.
    pub fn check(&self) -> Result<()> {
        if !(1..=5).contains(&self.max_degree) {
            return Err(Error::invalid("narx.max_degree", format!("must be between 1 and 5, got {}", self.max_degree)));
        }
        if !(1..=10).contains(&self.output_lags) {
            return Err(Error::invalid(
                "narx.output_lags",
                format!("must be between 1 and 10, got {}", self.output_lags),
            ));
        }
        if self.input_lags > 10 {
            return Err(Error::invalid("narx.input_lags", format!("must be at most 10, got {}", self.input_lags)));
        }
        if self.max_input_power == 0 || self.max_input_power > self.max_degree {
            return Err(Error::invalid("narx.max_input_power", "must be between 1 and max_degree"));
        }
        if !(2..=MAX_NARX_TERMS).contains(&self.max_terms) {
            return Err(Error::invalid(
                "narx.max_terms",
                format!("must be between 2 and {MAX_NARX_TERMS}, got {}", self.max_terms),
            ));
        }
        if self.coupling_lags > 10 {
            return Err(Error::invalid(
                "narx.coupling_lags",
                format!("must be at most 10, got {}", self.coupling_lags),
            ));
        }
        Ok(())
    }

    /// The candidate terms of mode `mode` of `modes`: constant, input powers, output powers, cross
    /// products, the other modes' displacements, then with `nonlinear_dampers` (and
    /// `damper_terms`) the damper law of the velocities.
    pub fn dictionary(&self, mode: usize, modes: usize, nonlinear_dampers: bool) -> Vec<NarxTerm> {
        let mut terms = vec![NarxTerm::CONSTANT];
        for input_power in 1..=self.max_input_power {
            for input_lag in 0..=self.input_lags {
                terms.push(NarxTerm::input(input_lag, input_power));
            }
        }
        for output_lag in 1..=self.output_lags {
            for output_power in 1..=self.max_degree {
                terms.push(NarxTerm::output(output_lag, output_power, None));
            }
        }
        if self.cross_terms {
            for output_lag in 1..=self.output_lags {
                for output_power in 1..self.max_degree {
                    for input_power in 1..=self.max_input_power.min(self.max_degree - output_power) {
                        for input_lag in 0..=self.input_lags {
                            terms.push(NarxTerm {
                                output_lag,
                                output_power,
                                input_lag,
                                input_power,
                                ..NarxTerm::CONSTANT
                            });
                        }
                    }
                }
            }
        }
        for other in (0..modes).filter(|&j| j != mode) {
            for lag in 1..=self.coupling_lags {
                terms.push(NarxTerm::output(lag, 1, Some(other)));
            }
        }
        if nonlinear_dampers && self.damper_terms {
            terms.push(NarxTerm::damper(DamperTerm::Law, 1, None));
            if self.coupling_lags > 0 {
                for other in (0..modes).filter(|&j| j != mode) {
                    terms.push(NarxTerm::damper(DamperTerm::Law, 1, Some(other)));
                    if self.secant_terms {
                        terms.push(NarxTerm::damper(DamperTerm::Modulated, 1, Some(other)));
                    }
                }
            }
        }
        terms
    }
}

/// Lagged value with the rest history before t = 0.
#[inline]
fn lagged(series: &[f64], t: usize, lag: usize, rest: f64) -> f64 {
    if lag > t { rest } else { series[t - lag] }
}

/// The series a model reads besides its own output: its input and the other modes' outputs, each
/// with its value at rest before t = 0.
#[derive(Debug, Clone, Copy)]
pub struct Exogenous<'a> {
    /// The input series.
    pub q: &'a [f64],
    /// The input at rest, before t = 0.
    pub q_rest: f64,
    /// Every mode's output series by mode index (the own entry is not read); empty without coupling.
    pub outputs: &'a [&'a [f64]],
    /// Their rest values.
    pub output_rests: &'a [f64],
    /// The law of velocity terms; `None` where the models have none.
    pub law: Option<&'a DamperLaw>,
    /// Per mode, the law's secant S at the first difference ending at each step of its output in
    /// `outputs` (computed once per record: these do not change with the model); empty, computed
    /// as needed.
    pub secants: &'a [&'a [f64]],
    /// The mode the model is of (whose knee its own damper terms use).
    pub mode: usize,
}

impl Exogenous<'_> {
    /// Value of a term that does not read the own output (input, constant or another mode's output).
    #[inline]
    fn external_value(&self, term: &NarxTerm, t: usize) -> f64 {
        self.value(term, &[], 0.0, t)
    }

    /// Value of a term at step t, `own` being the modelled mode's output series.
    #[inline(always)]
    fn value(&self, term: &NarxTerm, own: &[f64], own_rest: f64, t: usize) -> f64 {
        if let Some(kind) = term.damper {
            return self.damper_value(term, kind, own, own_rest, t);
        }
        let y = match term.output_mode {
            None if term.output_power == 0 => 0.0,
            None => lagged(own, t, term.output_lag, own_rest),
            Some(j) => lagged(self.outputs[j], t, term.output_lag, self.output_rests[j]),
        };
        term.value(y, lagged(self.q, t, term.input_lag, self.q_rest))
    }

    /// A damper term's value; out of line, so that the polynomial terms' path stays small enough
    /// to inline into the free run (inlined, the power's series made every term a call).
    #[inline(never)]
    fn damper_value(&self, term: &NarxTerm, kind: DamperTerm, own: &[f64], own_rest: f64, t: usize) -> f64 {
        let law = self.law.expect("a damper term is evaluated with its damper law");
        let lag = term.output_lag;
        let difference = |series: &[f64], rest: f64| lagged(series, t, lag, rest) - lagged(series, t, lag + 1, rest);
        let (source_difference, secant) = match term.output_mode {
            None => {
                let d = difference(own, own_rest);
                (d, law.secant(self.mode, d))
            }
            Some(j) => {
                let d = difference(self.outputs[j], self.output_rests[j]);
                (d, self.secants.get(j).map_or_else(|| law.secant(j, d), |s| lagged(s, t, lag, s[0])))
            }
        };
        match kind {
            DamperTerm::Law => source_difference * secant,
            // Of the own mode, Δ·S(Δ) = D(Δ).
            DamperTerm::Modulated => difference(own, own_rest) * secant,
        }
    }
}

/// Value of every term at step t given the own output series (measured or simulated) and the rest.
pub fn regressors(terms: &[NarxTerm], own: &[f64], own_rest: f64, ex: &Exogenous, t: usize, out: &mut [f64]) {
    for (o, term) in out.iter_mut().zip(terms) {
        *o = ex.value(term, own, own_rest, t);
    }
}

/// The model's rest output under a constant input q̄: the fixed point y = Σ θ_i g_i(y, …, y; q̄),
/// by Newton's method from `guess`. At rest every velocity is zero, and so is every damper term.
pub fn rest_output(terms: &[NarxTerm], theta: &[f64], q_rest: f64, output_rests: &[f64], guess: f64) -> Result<f64> {
    let mut y = guess;
    for _ in 0..100 {
        let (mut g, mut dg, mut magnitude) = (0.0, 0.0, 0.0);
        for (term, c) in terms.iter().zip(theta).filter(|(term, _)| term.damper.is_none()) {
            let output = term.output_mode.map_or(y, |j| output_rests[j]);
            let v = c * term.value(output, q_rest);
            g += v;
            magnitude += v.abs();
            if term.reads_own_output() {
                dg += c * term.output_derivative(y, q_rest);
            }
        }
        // Converged once the residual is down to the rounding of its own evaluation: the step's
        // rounding, ε/(1 − G′), is 10⁻¹³ for lightly damped modes, so a step test cannot decide.
        if (g - y).abs() <= 4.0 * f64::EPSILON * (magnitude + y.abs()) {
            return Ok(y);
        }
        let slope = 1.0 - dg;
        if slope.abs() < 1e-300 {
            break;
        }
        y += (g - y) / slope;
        if !y.is_finite() {
            break;
        }
    }
    Err(Error::Numerical("the NARX model has no rest state under the mean load".into()))
}

/// Output magnitude (scaled units) beyond which a free run counts as diverged: the data are O(1).
pub const DIVERGENCE_BOUND: f64 = 1.0e3;

/// Whether a simulated output has left the range a sane model can produce.
#[inline]
pub fn diverged(value: f64) -> bool {
    !value.is_finite() || value.abs() > DIVERGENCE_BOUND
}

/// Free run (Eq. 10) of one mode: ŷ(t) = Σ θ_i g_i(ẑ(t)) from the rest state, its own outputs fed
/// back, the exogenous series read as given. Writes `out[0..q.len()]`; fails when the run leaves
/// [−bound, bound] or stops being finite.
///
/// The terms that do not read the own output do not depend on the run, so their sum is formed
/// first, one pass per term over `out`; the step-by-step recursion then only evaluates the
/// feedback terms (two to four of a dictionary's ten), which makes structure selection, where
/// thousands of free runs score the candidates, several times faster.
pub fn free_run(terms: &[NarxTerm], theta: &[f64], ex: &Exogenous, rest: f64, out: &mut [f64]) -> Result<()> {
    let n = ex.q.len();
    out[..n].fill(0.0);
    let weighted = || terms.iter().zip(theta.iter().copied());
    let feedback: Vec<(&NarxTerm, f64)> = weighted().filter(|(term, _)| term.reads_own_output()).collect();
    for (term, c) in weighted().filter(|(term, _)| !term.reads_own_output()) {
        for (t, o) in out.iter_mut().enumerate().take(n).skip(1) {
            *o += c * ex.external_value(term, t);
        }
    }
    out[0] = rest;
    for t in 1..n {
        let mut value = out[t];
        for &(term, c) in &feedback {
            value += c * ex.value(term, out, rest, t);
        }
        if diverged(value) {
            return Err(Error::Numerical(format!("the free run diverged at step {t}")));
        }
        out[t] = value;
    }
    Ok(())
}

/// Mean relative error of a series (as in Mai et al.): Σ(y − ŷ)² / Σ(y − ȳ)².
pub fn relative_error(y: &[f64], y_hat: &[f64]) -> f64 {
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let numerator: f64 = y.iter().zip(y_hat).map(|(a, b)| (a - b).powi(2)).sum();
    let denominator: f64 = y.iter().map(|a| (a - mean).powi(2)).sum();
    numerator / denominator.max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dictionary_sizes_match_the_paper() {
        let paper = NarxOptions { coupling_lags: 0, ..Default::default() };
        assert_eq!(paper.dictionary(0, 3, false).len(), 10);
        assert_eq!(NarxOptions { cross_terms: true, ..paper.clone() }.dictionary(0, 3, false).len(), 22);
        assert_eq!(NarxOptions::default().dictionary(1, 3, false).len(), 10 + 4);
        let names: Vec<String> = NarxOptions::default().dictionary(1, 3, false).iter().map(|t| t.to_string()).collect();
        assert!(names.contains(&"y3(t-2)".to_string()) && !names.contains(&"y2(t-1)".to_string()));
        assert_eq!(names[..4], ["1", "Q(t)", "Q(t-1)", "Q(t-2)"]);
        assert!(names.contains(&"y(t-2)^3".to_string()));
    }

    /// A stable ARX(2) under a constant input rests at (c + b q̄)/(1 − a₁ − a₂), and its free run
    /// from rest under that input stays there.
    #[test]
    fn rest_state_and_free_run_of_a_linear_model() {
        let terms =
            [NarxTerm::CONSTANT, NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(2, 1, None)];
        let theta = [0.01, 0.02, 1.9, -0.95];
        let rest = rest_output(&terms, &theta, 2.0, &[], 0.0).unwrap();
        assert!((rest - (0.01 + 0.04) / (1.0 - 1.9 + 0.95)).abs() < 1e-12);
        let q = vec![2.0; 50];
        let ex = Exogenous { q: &q, q_rest: 2.0, outputs: &[], output_rests: &[], law: None, secants: &[], mode: 0 };
        let mut out = vec![0.0; 50];
        free_run(&terms, &theta, &ex, rest, &mut out).unwrap();
        assert!(out.iter().all(|v| (v - rest).abs() < 1e-12));
        // An unstable model is reported, not returned.
        let unstable = [0.0, 0.02, 2.1, -0.9];
        let q = vec![1.0; 5000];
        let ex = Exogenous { q: &q, q_rest: 1.0, outputs: &[], output_rests: &[], law: None, secants: &[], mode: 0 };
        let mut out = vec![0.0; 5000];
        assert!(free_run(&terms, &unstable, &ex, 0.0, &mut out).is_err());
    }
}
