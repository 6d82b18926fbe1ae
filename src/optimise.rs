//! Local minimisation of a smooth function of a few variables, for the refinement of NARX
//! coefficients on the simulation error: Nelder-Mead (derivative-free, the paper's choice) and
//! Levenberg-Marquardt (for least squares whose normal equations the caller can form). Both ask
//! the observer to stop once per iteration, and both say where they ended and why ([`Minimum`]),
//! so that a calibration can report a refinement that hit its cap.
//!
//! Hand-written: the crates that offer them (argmin, levenberg-marquardt) bring their own matrix
//! and problem abstractions for what is here a few dozen lines over `Vec<f64>`.

use crate::error::Result;
use crate::linalg::{cholesky, cholesky_solve};
use crate::progress::{Observer, check};
use serde::{Deserialize, Serialize};

/// Why a minimisation stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// The tolerance was met: a step improved the cost by less than its relative tolerance
    /// (Levenberg-Marquardt), or the simplex collapsed (Nelder-Mead).
    Converged,
    /// The iteration cap came first.
    IterationCap,
    /// No step improved the cost although the damping reached its cap (Levenberg-Marquardt): a
    /// minimum to the precision the cost is computed with.
    NoImprovingStep,
    /// The cost is not defined at the start (Levenberg-Marquardt: a free run that diverges); the
    /// start is returned.
    UndefinedStart,
}

/// Where a minimisation ended, what the cost was there, after how many iterations, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Minimum {
    /// The point where it ended.
    pub x: Vec<f64>,
    /// The cost there.
    pub cost: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// Why it stopped.
    pub stop: Stop,
}

/// Levenberg-Marquardt's iteration cap.
pub const LM_MAX_ITERATIONS: usize = 200;
/// Nelder-Mead's iteration cap per coordinate.
pub const NM_MAX_ITERATIONS_PER_COORDINATE: usize = 200;

/// The normal equations of a least-squares problem at a point: JᵀJ (row-major, n×n), Jᵀr and the
/// sum of squared residuals r.
pub struct NormalEquations {
    /// JᵀJ, row-major n×n.
    pub jtj: Vec<f64>,
    /// Jᵀr, one entry per variable.
    pub jtr: Vec<f64>,
    /// Σ r², the cost.
    pub sum_of_squares: f64,
}

/// Levenberg-Marquardt from `x`, scaled by diag(JᵀJ) (Marquardt's variant): at most
/// [`LM_MAX_ITERATIONS`] iterations, stopping when a step improves the sum of squares by less than
/// 10⁻¹⁰ relative or the damping passes 10¹². `normal_equations` returns None where the function is
/// not defined (the step is then refused). The cost reported is the sum of squares.
pub fn levenberg_marquardt(
    x: Vec<f64>,
    normal_equations: impl Fn(&[f64]) -> Option<NormalEquations>,
    observer: &dyn Observer,
) -> Result<Minimum> {
    let n = x.len();
    let mut x = x;
    let Some(mut current) = normal_equations(&x) else {
        return Ok(Minimum { x, cost: f64::INFINITY, iterations: 0, stop: Stop::UndefinedStart });
    };
    let mut lambda = 1e-3;
    let mut stop = Stop::IterationCap;
    let mut iterations = 0;
    while iterations < LM_MAX_ITERATIONS {
        iterations += 1;
        check(observer)?;
        let NormalEquations { jtj, jtr, sum_of_squares } = &current;
        let mut a = jtj.clone();
        for i in 0..n {
            a[i * n + i] += lambda * jtj[i * n + i].max(1e-300);
        }
        let mut step = jtr.clone();
        if !cholesky(&mut a, n) {
            lambda *= 10.0;
            continue;
        }
        cholesky_solve(&a, n, &mut step);
        let trial: Vec<f64> = x.iter().zip(&step).map(|(t, d)| t + d).collect();
        match normal_equations(&trial) {
            Some(next) if next.sum_of_squares < *sum_of_squares => {
                let improvement = (sum_of_squares - next.sum_of_squares) / sum_of_squares;
                x = trial;
                current = next;
                lambda = (lambda / 10.0).max(1e-12);
                if improvement < 1e-10 {
                    stop = Stop::Converged;
                    break;
                }
            }
            _ => {
                lambda *= 4.0;
                if lambda > 1e12 {
                    stop = Stop::NoImprovingStep;
                    break;
                }
            }
        }
    }
    Ok(Minimum { x, cost: current.sum_of_squares, iterations, stop })
}

/// Nelder-Mead from `x` (reflection 1, expansion 2, contraction ½, shrink ½; MATLAB's fminsearch
/// start simplex x + 5 % per coordinate), stopping when the simplex has collapsed to relative
/// 10⁻¹⁰ in both coordinates and values, or after [`NM_MAX_ITERATIONS_PER_COORDINATE`]·n
/// iterations.
pub fn nelder_mead(x: Vec<f64>, f: impl Fn(&[f64]) -> f64, observer: &dyn Observer) -> Result<Minimum> {
    let n = x.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    simplex.push((x.clone(), f(&x)));
    for i in 0..n {
        let mut vertex = x.clone();
        vertex[i] = if vertex[i] != 0.0 { vertex[i] * 1.05 } else { 0.00025 };
        let v = f(&vertex);
        simplex.push((vertex, v));
    }
    let centroid = |s: &[(Vec<f64>, f64)]| -> Vec<f64> {
        (0..n).map(|j| s[..n].iter().map(|(x, _)| x[j]).sum::<f64>() / n as f64).collect()
    };
    let along = |c: &[f64], x: &[f64], t: f64| -> Vec<f64> { c.iter().zip(x).map(|(c, x)| c + t * (x - c)).collect() };
    let mut stop = Stop::IterationCap;
    let mut iterations = 0;
    while iterations < NM_MAX_ITERATIONS_PER_COORDINATE * n {
        iterations += 1;
        check(observer)?;
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let best = simplex[0].1;
        let spread_f = simplex.iter().map(|s| (s.1 - best).abs()).fold(0.0, f64::max);
        let spread_x = simplex
            .iter()
            .flat_map(|s| s.0.iter().zip(&simplex[0].0).map(|(a, b)| (a - b).abs() / b.abs().max(1e-12)))
            .fold(0.0, f64::max);
        if spread_f <= 1e-10 * best.abs().max(1e-300) && spread_x <= 1e-10 {
            stop = Stop::Converged;
            break;
        }
        let c = centroid(&simplex);
        let worst = simplex[n].clone();
        let reflected = along(&c, &worst.0, -1.0);
        let fr = f(&reflected);
        if fr < simplex[0].1 {
            let expanded = along(&c, &worst.0, -2.0);
            let fe = f(&expanded);
            simplex[n] = if fe < fr { (expanded, fe) } else { (reflected, fr) };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (reflected, fr);
        } else {
            let contracted = if fr < worst.1 { along(&c, &reflected, 0.5) } else { along(&c, &worst.0, 0.5) };
            let fc = f(&contracted);
            if fc < worst.1.min(fr) {
                simplex[n] = (contracted, fc);
            } else {
                let best_x = simplex[0].0.clone();
                for s in simplex.iter_mut().skip(1) {
                    s.0 = along(&best_x, &s.0, 0.5);
                    s.1 = f(&s.0);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (x, cost) = simplex.swap_remove(0);
    Ok(Minimum { x, cost, iterations, stop })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;

    /// Rosenbrock's valley, minimum 0 at (1, 1), from the textbook start (−1.2, 1).
    #[test]
    fn nelder_mead_finds_the_rosenbrock_minimum() {
        let rosenbrock = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let minimum = nelder_mead(vec![-1.2, 1.0], rosenbrock, &Silent).unwrap();
        let x = &minimum.x;
        assert!((x[0] - 1.0).abs() < 1e-4 && (x[1] - 1.0).abs() < 1e-4, "{x:?}");
        assert_eq!(minimum.stop, Stop::Converged);
        assert!(minimum.cost < 1e-8 && minimum.cost == rosenbrock(x), "{minimum:?}");
        assert!(minimum.iterations > 10 && minimum.iterations < NM_MAX_ITERATIONS_PER_COORDINATE * 2);
        // On a function without a minimum the cap comes first, and it says so.
        let capped = nelder_mead(vec![-1.2, 1.0], |x: &[f64]| x[0].sin() * 1e-300 + x[1], &Silent).unwrap();
        assert_eq!((capped.stop, capped.iterations), (Stop::IterationCap, NM_MAX_ITERATIONS_PER_COORDINATE * 2));
    }

    /// The exponential fit y = a·e^{b t} to exact data returns (a, b) = (2, −0.5).
    #[test]
    fn levenberg_marquardt_fits_an_exponential() {
        let t: Vec<f64> = (0..20).map(|i| i as f64 * 0.25).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.5 * t).exp()).collect();
        let normal_equations = |p: &[f64]| {
            let mut jtj = vec![0.0; 4];
            let (mut jtr, mut sum_of_squares) = (vec![0.0; 2], 0.0);
            for (t, y) in t.iter().zip(&y) {
                let e = (p[1] * t).exp();
                let (r, j) = (y - p[0] * e, [e, p[0] * t * e]);
                sum_of_squares += r * r;
                for a in 0..2 {
                    jtr[a] += j[a] * r;
                    for b in 0..2 {
                        jtj[a * 2 + b] += j[a] * j[b];
                    }
                }
            }
            Some(NormalEquations { jtj, jtr, sum_of_squares })
        };
        let minimum = levenberg_marquardt(vec![1.0, 0.0], normal_equations, &Silent).unwrap();
        let x = &minimum.x;
        assert!((x[0] - 2.0).abs() < 1e-8 && (x[1] + 0.5).abs() < 1e-8, "{x:?}");
        assert!(minimum.cost < 1e-20 && minimum.iterations < 100, "{minimum:?}");
        assert!(matches!(minimum.stop, Stop::Converged | Stop::NoImprovingStep), "{minimum:?}");
        let undefined = levenberg_marquardt(vec![1.0, 0.0], |_: &[f64]| None, &Silent).unwrap();
        assert_eq!((undefined.stop, undefined.iterations, undefined.x), (Stop::UndefinedStart, 0, vec![1.0, 0.0]));
    }
}
