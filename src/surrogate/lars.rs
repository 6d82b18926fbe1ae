//! Least angle regression (Efron, Hastie, Johnstone & Tibshirani 2004) in covariance form.
//!
//! Only the Gram matrix XᵀX and the correlations Xᵀy are needed, so the NARX structure selection can
//! stream 90 000-row regressions into a P×P matrix, and the PCE selection works on ΨᵀΨ alike. The
//! caller centres and scales the columns when that is wanted; this module follows the plain
//! algorithm, as scikit-learn's `lars_path(method="lar")` does.

use crate::linalg::{cholesky, cholesky_solve};

/// One LARS step: the active set after it (in order of entry) and the coefficients of all columns.
#[derive(Debug, Clone, PartialEq)]
pub struct LarsStep {
    /// Columns in the active set, in order of entry.
    pub active: Vec<usize>,
    /// Coefficient of every column, zero outside the active set.
    pub coefficients: Vec<f64>,
}

/// The LARS path on Gram `gram` (P×P row-major) and correlations `xty`, for at most `max_steps`
/// steps. Stops early when the residual correlations vanish or the active Gram matrix becomes
/// singular (a column that is a combination of active ones cannot enter).
pub fn lars_path(gram: &[f64], xty: &[f64], max_steps: usize) -> Vec<LarsStep> {
    let p = xty.len();
    let mut beta = vec![0.0; p];
    let mut active: Vec<usize> = Vec::new();
    let mut path = Vec::new();
    let mut correlation = xty.to_vec();
    let scale = xty.iter().fold(0.0f64, |m, c| m.max(c.abs())).max(f64::MIN_POSITIVE);
    let mut entering = argmax_abs(&correlation, &active);
    while let Some(j) = entering {
        if active.len() >= max_steps.min(p) {
            break;
        }
        active.push(j);
        let big_c = correlation[j].abs();
        if big_c <= 1e-12 * scale {
            active.pop();
            break;
        }
        let k = active.len();
        let signs: Vec<f64> = active.iter().map(|&a| if correlation[a] >= 0.0 { 1.0 } else { -1.0 }).collect();
        let mut g_a: Vec<f64> = (0..k * k).map(|idx| gram[active[idx / k] * p + active[idx % k]]).collect();
        if !cholesky(&mut g_a, k) {
            active.pop();
            break;
        }
        let mut q = signs.clone();
        cholesky_solve(&g_a, k, &mut q);
        let norm: f64 = signs.iter().zip(&q).map(|(s, x)| s * x).sum();
        let a_a = 1.0 / norm.sqrt();
        let w: Vec<f64> = q.iter().map(|x| a_a * x).collect();
        // a_j = Σ_{i∈A} G_{j,i} w_i for every column.
        let a: Vec<f64> =
            (0..p).map(|col| active.iter().zip(&w).map(|(&i, wi)| gram[col * p + i] * wi).sum()).collect();
        let mut gamma = big_c / a_a;
        let mut next = None;
        for col in 0..p {
            if active.contains(&col) {
                continue;
            }
            for candidate in [(big_c - correlation[col]) / (a_a - a[col]), (big_c + correlation[col]) / (a_a + a[col])]
            {
                if candidate > 1e-15 * gamma && candidate < gamma {
                    gamma = candidate;
                    next = Some(col);
                }
            }
        }
        for (&i, wi) in active.iter().zip(&w) {
            beta[i] += gamma * wi;
        }
        for col in 0..p {
            correlation[col] -= gamma * a[col];
        }
        path.push(LarsStep { active: active.clone(), coefficients: beta.clone() });
        entering = next;
    }
    path
}

fn argmax_abs(values: &[f64], excluded: &[usize]) -> Option<usize> {
    values
        .iter()
        .enumerate()
        .filter(|(i, _)| !excluded.contains(i))
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Deserialize)]
    struct Fixture {
        x: Vec<Vec<f64>>,
        y: Vec<f64>,
        active: Vec<usize>,
        coefs: Vec<Vec<f64>>,
    }

    /// The path of scikit-learn's `lars_path(X, y, method="lar")` on a random problem
    /// (tests/fixtures/generate.py): the same order of entry and the same coefficients at every step.
    #[test]
    fn matches_scikit_learn() {
        let fixture: Fixture =
            serde_json::from_str(include_str!("../../tests/fixtures/lars.json")).expect("fixture parses");
        let (n, p) = (fixture.x.len(), fixture.x[0].len());
        let gram: Vec<f64> =
            (0..p * p).map(|k| (0..n).map(|r| fixture.x[r][k / p] * fixture.x[r][k % p]).sum()).collect();
        let xty: Vec<f64> = (0..p).map(|c| (0..n).map(|r| fixture.x[r][c] * fixture.y[r]).sum()).collect();
        let path = lars_path(&gram, &xty, p);
        assert_eq!(path.last().unwrap().active, fixture.active);
        // sklearn's coefs[:, k] holds the coefficients after k steps (column 0 is all zeros).
        for (step, lars) in path.iter().enumerate() {
            for col in 0..p {
                let expected = fixture.coefs[col][step + 1];
                assert!(
                    (lars.coefficients[col] - expected).abs() < 1e-9 * (1.0 + expected.abs()),
                    "step {step} col {col}"
                );
            }
        }
    }
}
