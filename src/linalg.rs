//! Dense Cholesky on small row-major matrices, in place and without allocation.
//!
//! The hot loops (a 40×40 factorisation per wind frequency, a k×k Newton system per time step) call
//! these millions of times; faer's general-purpose entry points allocate and dispatch per call, which
//! costs more than the arithmetic at these sizes. Everything larger goes through faer.

/// Factors the symmetric positive semi-definite `a` (n×n, row-major, lower triangle read) in place
/// into its lower Cholesky factor, through column `last` only. A pivot that rounding drives to or
/// below zero yields a zero column (the factor of a semi-definite matrix).
pub fn cholesky_through_column(a: &mut [f64], n: usize, last: usize) {
    for k in 0..=last {
        let mut d = a[k * n + k];
        for r in 0..k {
            d -= a[k * n + r] * a[k * n + r];
        }
        let pivot = if d > 0.0 { d.sqrt() } else { 0.0 };
        a[k * n + k] = pivot;
        for j in k + 1..n {
            if pivot == 0.0 {
                a[j * n + k] = 0.0;
                continue;
            }
            let mut v = a[j * n + k];
            for r in 0..k {
                v -= a[j * n + r] * a[k * n + r];
            }
            a[j * n + k] = v / pivot;
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
        let s: f64 = (0..i).map(|k| l[i * n + k] * b[k]).sum();
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
