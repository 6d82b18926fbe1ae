//! Dense Cholesky on small row-major matrices, in place and without allocation.
//!
//! The hot loops (a 40×40 factorisation per wind frequency, a k×k Newton system per time step) call
//! these millions of times; faer's general-purpose entry points allocate and dispatch per call, which
//! costs more than the arithmetic at these sizes. Everything larger goes through faer.

/// Σ x_i y_i in four interleaved partial sums: the compiler keeps them in one vector register, and
/// the chain of dependent additions is a quarter as long as a left-to-right sum's (the full-order
/// integrator's Newton factorisations spent most of their time waiting on that chain).
#[inline]
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut sums = [0.0; 4];
    let (x4, y4) = (x.chunks_exact(4), y.chunks_exact(4));
    let tail: f64 = x4.remainder().iter().zip(y4.remainder()).map(|(a, b)| a * b).sum();
    for (a, b) in x4.zip(y4) {
        for k in 0..4 {
            sums[k] += a[k] * b[k];
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) + tail
}

/// Factors the symmetric positive semi-definite `a` (n×n, row-major, lower triangle read) in place
/// into its lower Cholesky factor, through column `last` only. A pivot that rounding drives to or
/// below zero yields a zero column (the factor of a semi-definite matrix).
pub fn cholesky_through_column(a: &mut [f64], n: usize, last: usize) {
    for k in 0..=last {
        let (above, below) = a.split_at_mut((k + 1) * n);
        let row_k = &mut above[k * n..];
        let d = row_k[k] - dot(&row_k[..k], &row_k[..k]);
        let pivot = if d > 0.0 { d.sqrt() } else { 0.0 };
        row_k[k] = pivot;
        for row_j in below.chunks_exact_mut(n) {
            row_j[k] = if pivot == 0.0 { 0.0 } else { (row_j[k] - dot(&row_j[..k], &row_k[..k])) / pivot };
        }
    }
}

/// Full in-place Cholesky factorisation; `false` if the matrix is not positive definite.
pub fn cholesky(a: &mut [f64], n: usize) -> bool {
    cholesky_through_column(a, n, n - 1);
    (0..n).all(|k| a[k * n + k] > 0.0)
}

/// Solves L Lᵀ x = b in place given the factor from [`cholesky`].
pub fn cholesky_solve(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let s = dot(&l[i * n..i * n + i], &b[..i]);
        b[i] = (b[i] - s) / l[i * n + i];
    }
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k * n + i] * b[k]).sum();
        b[i] = (b[i] - s) / l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dot_equals_the_plain_sum() {
        for len in [0, 1, 3, 4, 7, 40] {
            let x: Vec<f64> = (0..len).map(|i| 0.5 + i as f64).collect();
            let y: Vec<f64> = (0..len).map(|i| 1.0 / (1.0 + i as f64)).collect();
            let plain: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
            assert!((dot(&x, &y) - plain).abs() <= 1e-14 * plain.abs().max(1.0), "length {len}");
        }
    }

    #[test]
    fn solves_a_known_system() {
        // A = [[4, 2, 0.4], [2, 5, 1], [0.4, 1, 3]], x = (1, −2, 0.5).
        let a = [4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let x = [1.0, -2.0, 0.5];
        let mut b: Vec<f64> = (0..3).map(|i| (0..3).map(|j| a[i * 3 + j] * x[j]).sum()).collect();
        let mut l = a;
        assert!(cholesky(&mut l, 3));
        cholesky_solve(&l, 3, &mut b);
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-14);
        }
        let mut singular = [1.0, 1.0, 1.0, 1.0];
        assert!(!cholesky(&mut singular, 2));
    }
}
