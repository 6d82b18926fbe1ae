//! NARX models of one modal coordinate (Eqs. 6-7 and 18): the candidate terms, their evaluation on
//! measured (one-step-ahead) or simulated (free-run) outputs, and the free run itself.
//!
//! Series are scaled to O(1) by per-mode constants before they reach a model. Before t = 0 the
//! structure is at rest under the mean load: the output history is the model's own fixed point under
//! the mean input, which is what the reference's static start means for the metamodel.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt;

/// One candidate term y(t − output_lag)^output_power · Q(t − input_lag)^input_power (Eq. 18); all
/// powers zero is the constant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct NarxTerm {
    pub output_lag: usize,
    pub output_power: u32,
    pub input_lag: usize,
    pub input_power: u32,
}

impl NarxTerm {
    pub const CONSTANT: NarxTerm = NarxTerm { output_lag: 0, output_power: 0, input_lag: 0, input_power: 0 };

    pub fn is_constant(&self) -> bool {
        self.output_power == 0 && self.input_power == 0
    }

    /// Value given y(t − output_lag) and Q(t − input_lag).
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
        if self.output_power > 0 {
            parts.push(format!("y(t-{}){}", self.output_lag, exponent(self.output_power)));
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
#[serde(default, deny_unknown_fields)]
pub struct NarxOptions {
    /// Largest total degree l₁ + l₂ of a term.
    pub max_degree: u32,
    /// Output lags 1 ..= output_lags.
    pub output_lags: usize,
    /// Input lags 0 ..= input_lags.
    pub input_lags: usize,
    /// Largest power of the input in a term.
    pub max_input_power: u32,
    /// Whether products of an output power and an input power are candidates.
    pub cross_terms: bool,
    /// Most terms in a selected model (the constant included).
    pub max_terms: usize,
}

impl Default for NarxOptions {
    fn default() -> Self {
        NarxOptions {
            max_degree: 3,
            output_lags: 2,
            input_lags: 2,
            max_input_power: 1,
            cross_terms: false,
            max_terms: 8,
        }
    }
}

impl NarxOptions {
    pub fn validate(&self) -> Result<()> {
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
        if self.max_terms < 2 {
            return Err(Error::invalid("narx.max_terms", "must be at least 2"));
        }
        Ok(())
    }

    /// The candidate terms: constant, input powers, output powers, then cross products.
    pub fn dictionary(&self) -> Vec<NarxTerm> {
        let mut terms = vec![NarxTerm::CONSTANT];
        for input_power in 1..=self.max_input_power {
            for input_lag in 0..=self.input_lags {
                terms.push(NarxTerm { output_lag: 0, output_power: 0, input_lag, input_power });
            }
        }
        for output_lag in 1..=self.output_lags {
            for output_power in 1..=self.max_degree {
                terms.push(NarxTerm { output_lag, output_power, input_lag: 0, input_power: 0 });
            }
        }
        if self.cross_terms {
            for output_lag in 1..=self.output_lags {
                for output_power in 1..self.max_degree {
                    for input_power in 1..=self.max_input_power.min(self.max_degree - output_power) {
                        for input_lag in 0..=self.input_lags {
                            terms.push(NarxTerm { output_lag, output_power, input_lag, input_power });
                        }
                    }
                }
            }
        }
        terms
    }
}

/// Longest lag among `terms` (the history a recursion needs).
pub fn max_lag(terms: &[NarxTerm]) -> usize {
    terms.iter().map(|t| t.output_lag.max(t.input_lag)).max().unwrap_or(0)
}

/// Lagged value with the rest history before t = 0.
#[inline]
fn lagged(series: &[f64], t: usize, lag: usize, rest: f64) -> f64 {
    if lag > t { rest } else { series[t - lag] }
}

/// Value of every term at step t given output and input series (scaled) and their rest values.
pub fn regressors(terms: &[NarxTerm], y: &[f64], q: &[f64], t: usize, rest: (f64, f64), out: &mut [f64]) {
    for (o, term) in out.iter_mut().zip(terms) {
        *o = term.value(lagged(y, t, term.output_lag, rest.0), lagged(q, t, term.input_lag, rest.1));
    }
}

/// The model's rest output under a constant input q̄: the fixed point y = Σ θ_i g_i(y, …, y; q̄),
/// by Newton's method from `guess`.
pub fn rest_output(terms: &[NarxTerm], theta: &[f64], q_rest: f64, guess: f64) -> Result<f64> {
    let mut y = guess;
    for _ in 0..100 {
        let (mut g, mut dg, mut magnitude) = (0.0, 0.0, 0.0);
        for (term, c) in terms.iter().zip(theta) {
            let v = c * term.value(y, q_rest);
            g += v;
            magnitude += v.abs();
            dg += c * term.output_derivative(y, q_rest);
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

/// Free run (Eq. 10): ŷ(t) = Σ θ_i g_i(ẑ(t)) from the rest state, the outputs fed back. Writes
/// `out[0..q.len()]`; fails when the run leaves [−bound, bound] or stops being finite.
pub fn free_run(terms: &[NarxTerm], theta: &[f64], q: &[f64], rest: (f64, f64), out: &mut [f64]) -> Result<()> {
    let n = q.len();
    out[0] = rest.0;
    for t in 1..n {
        let mut value = 0.0;
        for (term, c) in terms.iter().zip(theta) {
            value += c * term.value(lagged(out, t, term.output_lag, rest.0), lagged(q, t, term.input_lag, rest.1));
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
        assert_eq!(NarxOptions::default().dictionary().len(), 10);
        assert_eq!(NarxOptions { cross_terms: true, ..Default::default() }.dictionary().len(), 22);
        let names: Vec<String> = NarxOptions::default().dictionary().iter().map(|t| t.to_string()).collect();
        assert_eq!(names[..4], ["1", "Q(t)", "Q(t-1)", "Q(t-2)"]);
        assert!(names.contains(&"y(t-2)^3".to_string()));
    }

    /// A stable ARX(2) under a constant input rests at (c + b q̄)/(1 − a₁ − a₂), and its free run
    /// from rest under that input stays there.
    #[test]
    fn rest_state_and_free_run_of_a_linear_model() {
        let terms = [
            NarxTerm::CONSTANT,
            NarxTerm { output_lag: 0, output_power: 0, input_lag: 0, input_power: 1 },
            NarxTerm { output_lag: 1, output_power: 1, input_lag: 0, input_power: 0 },
            NarxTerm { output_lag: 2, output_power: 1, input_lag: 0, input_power: 0 },
        ];
        let theta = [0.01, 0.02, 1.9, -0.95];
        let rest = rest_output(&terms, &theta, 2.0, 0.0).unwrap();
        assert!((rest - (0.01 + 0.04) / (1.0 - 1.9 + 0.95)).abs() < 1e-12);
        let q = vec![2.0; 50];
        let mut out = vec![0.0; 50];
        free_run(&terms, &theta, &q, (rest, 2.0), &mut out).unwrap();
        assert!(out.iter().all(|v| (v - rest).abs() < 1e-12));
        // An unstable model is reported, not returned.
        let unstable = [0.0, 0.02, 2.1, -0.9];
        let mut out = vec![0.0; 5000];
        assert!(free_run(&terms, &unstable, &vec![1.0; 5000], (0.0, 1.0), &mut out).is_err());
    }
}
