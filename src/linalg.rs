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

/// out = M x for the row-major square M.
pub fn multiply_into(out: &mut [f64], matrix: &[f64], x: &[f64]) {
    for (o, row) in out.iter_mut().zip(matrix.chunks_exact(x.len())) {
        *o = dot(row, x);
    }
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

/// Full in-place Cholesky factorisation A = UᵀU of the symmetric `a` (n×n, row-major, upper
/// triangle read) into its upper factor U; `false` if the matrix is not positive definite.
/// The diagonal holds the reciprocals 1/U_kk: the solves then multiply where they would divide, and
/// a division's latency is most of the time of each link in a substitution's chain.
///
/// Right-looking: each step scales row k and subtracts its multiples from the rows below, which are
/// contiguous runs in row-major storage, so the update vectorises with no reduction. (The factor of
/// the semi-definite spectral matrices, [`cholesky_through_column`], is the lower one because its
/// callers read L's columns for a few leading modes only.)
pub fn cholesky(a: &mut [f64], n: usize) -> bool {
    for k in 0..n {
        let (above, below) = a.split_at_mut((k + 1) * n);
        let row_k = &mut above[k * n..];
        let d = row_k[k];
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let inverse = 1.0 / d.sqrt();
        row_k[k] = inverse;
        row_k[k + 1..].iter_mut().for_each(|x| *x *= inverse);
        for (offset, row_i) in below.chunks_exact_mut(n).enumerate() {
            let i = k + 1 + offset;
            axpy(&mut row_i[i..], -row_k[i], &row_k[i..]);
        }
    }
    true
}

/// y += α x.
#[inline]
fn axpy(y: &mut [f64], alpha: f64, x: &[f64]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += alpha * x;
    }
}

/// Solves Uᵀ z = b in place for the factor U of [`cholesky`] (so that |z|² = bᵀA⁻¹b).
pub fn forward_substitute(u: &[f64], n: usize, b: &mut [f64]) {
    for (k, row) in u.chunks_exact(n).enumerate() {
        let z = b[k] * row[k];
        b[k] = z;
        axpy(&mut b[k + 1..], -z, &row[k + 1..]);
    }
}

/// Solves UᵀU x = b in place given the factor from [`cholesky`].
pub fn cholesky_solve(u: &[f64], n: usize, b: &mut [f64]) {
    forward_substitute(u, n, b);
    for (i, row) in u.chunks_exact(n).enumerate().rev() {
        let s = dot(&row[i + 1..], &b[i + 1..]);
        b[i] = (b[i] - s) * row[i];
    }
}

/// Changes the factor U of A (from [`cholesky`]) into that of A + σ x xᵀ, σ = ±1, in O(n²) with
/// plane (σ = 1) or hyperbolic (σ = −1) rotations; `x` is consumed. Entries of `x` before `first`
/// must be zero: the rows above it do not change. `false`, with U spoiled, if a downdate would leave
/// A + σ x xᵀ not positive definite.
pub fn cholesky_rank_one(u: &mut [f64], n: usize, x: &mut [f64], sign: f64, first: usize) -> bool {
    for k in first..n {
        let row = &mut u[k * n..(k + 1) * n];
        let (pivot, xk) = (1.0 / row[k], x[k]);
        let squared = pivot * pivot + sign * xk * xk;
        if squared.is_nan() || squared <= 0.0 {
            return false;
        }
        let updated = squared.sqrt();
        let (c, s) = (updated * row[k], xk * row[k]);
        let (inverse_c, signed_s) = (pivot / updated, sign * s);
        row[k] = 1.0 / updated;
        for (r, xj) in row[k + 1..].iter_mut().zip(&mut x[k + 1..]) {
            *r = (*r + signed_s * *xj) * inverse_c;
            *xj = c * *xj - s * *r;
        }
    }
    true
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

    /// A 12×12 symmetric positive definite matrix with a dominant diagonal and dense coupling.
    fn spd(n: usize) -> Vec<f64> {
        (0..n * n)
            .map(|k| {
                let (i, j) = ((k / n) as f64, (k % n) as f64);
                1.0 / (1.0 + (i - j).abs()) + if i == j { 2.0 + 0.1 * i } else { 0.0 }
            })
            .collect()
    }

    /// Updating and then downdating the factor by a vector whose leading entries are zero gives the
    /// factor of the changed matrix, as factoring it afresh does; A x = b checks it end to end.
    #[test]
    fn rank_one_changes_equal_a_fresh_factorisation() {
        let n = 12;
        let a = spd(n);
        let first = 4;
        let x: Vec<f64> = (0..n).map(|i| if i < first { 0.0 } else { 0.3 + 0.05 * i as f64 }).collect();
        for (sign, scale) in [(1.0, 3.0), (-1.0, 0.9)] {
            let changed: Vec<f64> = (0..n * n).map(|k| a[k] + sign * scale * scale * x[k / n] * x[k % n]).collect();
            let mut fresh = changed.clone();
            assert!(cholesky(&mut fresh, n));
            let mut updated = a.clone();
            assert!(cholesky(&mut updated, n));
            let mut vector: Vec<f64> = x.iter().map(|v| scale * v).collect();
            assert!(cholesky_rank_one(&mut updated, n, &mut vector, sign, first));
            for i in 0..n {
                for j in i..n {
                    let (u, f) = (updated[i * n + j], fresh[i * n + j]);
                    assert!((u - f).abs() <= 1e-13 * f.abs().max(1.0), "({i}, {j}): {u} vs {f}");
                }
            }
            let solution: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
            let mut b = vec![0.0; n];
            multiply_into(&mut b, &changed, &solution);
            cholesky_solve(&updated, n, &mut b);
            assert!(b.iter().zip(&solution).all(|(x, y)| (x - y).abs() < 1e-12), "{b:?}");
        }
        // Downdating past positive definiteness is refused.
        let mut factor = a.clone();
        assert!(cholesky(&mut factor, n));
        let mut too_much: Vec<f64> = x.iter().map(|v| 10.0 * v).collect();
        assert!(!cholesky_rank_one(&mut factor, n, &mut too_much, -1.0, first));
    }

    /// |z|² of Uᵀz = b is bᵀA⁻¹b, which the full solve gives independently.
    #[test]
    fn forward_substitution_gives_the_inverse_quadratic_form() {
        let n = 12;
        let mut factor = spd(n);
        assert!(cholesky(&mut factor, n));
        let b: Vec<f64> = (0..n).map(|i| 1.0 - 0.1 * i as f64).collect();
        let mut z = b.clone();
        forward_substitute(&factor, n, &mut z);
        let mut x = b.clone();
        cholesky_solve(&factor, n, &mut x);
        let (norm, form) = (dot(&z, &z), dot(&b, &x));
        assert!((norm - form).abs() < 1e-14 * form, "{norm} vs {form}");
    }
}
