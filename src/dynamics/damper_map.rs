//! G, the map from the unknowns of a damper solve to the dampers' axial velocities, and the three
//! products a Newton iteration takes of it: G s, Gᵀ f and Gᵀ diag(w) G.
//!
//! A full-order model's rows are sparse (a damper joins two floors: two to six unknowns of the
//! hundreds), a reduced-order model's dense (every mode moves every damper). Dense, G is kept
//! column by column, so that each product is a pass over contiguous dampers that vectorises: the
//! three-dimensional building's 160 dampers on six modes made the row-by-row products, an index
//! and a weight at a time, most of a reduced storm's cost.

/// A dense Gram's multiply-adds run in independent vector chains ([`dots`]), those of a rank-one
/// change of the factor one after another behind its square roots and divisions, so
/// [`DamperMap::gram_cost`] counts the Gram's at this discount, in the rank-one changes' currency
/// (chosen by timing, not derived: an estimate of some 0.15 cycles against 2.5 a multiply-add, and
/// the probe below). Counted at par, a 900 s storm of `frame40-3d` made 10.5 rank-one
/// changes and 0.09 factorisations per step (530 and 498 ms); at this discount 0.2 and 0.43 (447
/// and 443 ms).
const DENSE_GRAM_DISCOUNT: usize = 16;

/// G with rows r_d, sparse or dense.
#[derive(Debug, Clone)]
pub(super) enum DamperMap {
    /// r_d as (index, entry) pairs.
    Sparse(Vec<Vec<(usize, f64)>>),
    /// Every row full: column i (the unknown i's weight on every damper) at
    /// `columns[i·dampers..(i + 1)·dampers]`.
    Dense { dampers: usize, columns: Vec<f64> },
}

impl DamperMap {
    /// The map of `rows` over `size` unknowns, dense when every row holds every unknown in order.
    pub(super) fn new(rows: Vec<Vec<(usize, f64)>>, size: usize) -> Self {
        let full = |row: &Vec<(usize, f64)>| row.len() == size && row.iter().enumerate().all(|(k, &(i, _))| i == k);
        if size == 0 || rows.is_empty() || !rows.iter().all(full) {
            return DamperMap::Sparse(rows);
        }
        let dampers = rows.len();
        let mut columns = vec![0.0; size * dampers];
        for (d, row) in rows.iter().enumerate() {
            for &(i, w) in row {
                columns[i * dampers + d] = w;
            }
        }
        DamperMap::Dense { dampers, columns }
    }

    /// The number of dampers.
    pub(super) fn len(&self) -> usize {
        match self {
            DamperMap::Sparse(rows) => rows.len(),
            DamperMap::Dense { dampers, .. } => *dampers,
        }
    }

    /// The lowest unknown row d weighs (`size` for an empty row).
    pub(super) fn first_index(&self, d: usize, size: usize) -> usize {
        match self {
            DamperMap::Sparse(rows) => rows[d].iter().map(|&(i, _)| i).min().unwrap_or(size),
            DamperMap::Dense { .. } => 0,
        }
    }

    /// Multiply-adds of Gᵀ diag(w) G over `size` unknowns, a dense map's at a discount for their
    /// vector lanes ([`DENSE_GRAM_DISCOUNT`]).
    pub(super) fn gram_cost(&self, size: usize) -> usize {
        match self {
            DamperMap::Sparse(rows) => rows.iter().map(|row| row.len() * row.len()).sum(),
            DamperMap::Dense { dampers, .. } => dampers * size * (size + 1) / 2 / DENSE_GRAM_DISCOUNT,
        }
    }

    /// out = G s.
    pub(super) fn velocities(&self, s: &[f64], out: &mut [f64]) {
        match self {
            DamperMap::Sparse(rows) => {
                for (v, row) in out.iter_mut().zip(rows) {
                    *v = row.iter().map(|&(i, w)| w * s[i]).sum();
                }
            }
            DamperMap::Dense { dampers, columns } => {
                out.iter_mut().for_each(|v| *v = 0.0);
                for (column, &x) in columns.chunks_exact(*dampers).zip(s) {
                    out.iter_mut().zip(column).for_each(|(v, w)| *v += w * x);
                }
            }
        }
    }

    /// out += Gᵀ f.
    pub(super) fn add_transposed(&self, forces: &[f64], out: &mut [f64]) {
        match self {
            DamperMap::Sparse(rows) => {
                for (row, f) in rows.iter().zip(forces) {
                    for &(i, w) in row {
                        out[i] += w * f;
                    }
                }
            }
            DamperMap::Dense { dampers, columns } => {
                // Gᵀ f was a twelfth of a three-dimensional storm as one dot product per column.
                let column = |i: usize| &columns[i * dampers..(i + 1) * dampers];
                each_dot(column, 0..out.len(), forces, |m, x| out[m] += x);
            }
        }
    }

    /// matrix += Gᵀ diag(weights) G, row-major size×size, both triangles; `scratch` holds a
    /// column's worth of work space for the dense map.
    pub(super) fn add_weighted_gram(&self, weights: &[f64], matrix: &mut [f64], scratch: &mut Vec<f64>) {
        let n = (matrix.len() as f64).sqrt().round() as usize;
        match self {
            DamperMap::Sparse(rows) => {
                for (row, &weight) in rows.iter().zip(weights) {
                    for &(i, wi) in row {
                        for &(j, wj) in row {
                            matrix[i * n + j] += weight * wi * wj;
                        }
                    }
                }
            }
            DamperMap::Dense { dampers, columns } => {
                scratch.resize(*dampers, 0.0);
                let column = |i: usize| &columns[i * dampers..(i + 1) * dampers];
                for i in 0..n {
                    scratch.iter_mut().zip(column(i)).zip(weights).for_each(|((s, g), w)| *s = w * g);
                    each_dot(column, i..n, scratch, |j, entry| {
                        matrix[i * n + j] += entry;
                        if j != i {
                            matrix[j * n + i] += entry;
                        }
                    });
                }
            }
        }
    }

    /// out += scale · r_d.
    pub(super) fn add_row(&self, d: usize, scale: f64, out: &mut [f64]) {
        match self {
            DamperMap::Sparse(rows) => {
                for &(i, w) in &rows[d] {
                    out[i] += scale * w;
                }
            }
            DamperMap::Dense { dampers, columns } => {
                for (o, column) in out.iter_mut().zip(columns.chunks_exact(*dampers)) {
                    *o += scale * column[d];
                }
            }
        }
    }
}

/// The dot products of K columns with `f`, each in eight interleaved partial sums: 2K independent
/// chains of vector additions in one pass over the dampers, where a dot product at a time waits on
/// its own chain (the dense map's products were latency-bound that way).
#[inline]
fn dots<const K: usize>(columns: [&[f64]; K], f: &[f64]) -> [f64; K] {
    let mut sums = [[0.0; 8]; K];
    let f8 = f.chunks_exact(8);
    let tail_start = f.len() - f8.remainder().len();
    for (c, chunk) in f8.enumerate() {
        let at = c * 8;
        for (sum, column) in sums.iter_mut().zip(&columns) {
            let column = &column[at..at + 8];
            for k in 0..8 {
                sum[k] += column[k] * chunk[k];
            }
        }
    }
    std::array::from_fn(|j| {
        let s = &sums[j];
        let tail: f64 = columns[j][tail_start..].iter().zip(&f[tail_start..]).map(|(a, b)| a * b).sum();
        ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7])) + tail
    })
}

/// Calls `each(j, column(j)·f)` for every j of `range`, the dot products four at a time, then two,
/// then one ([`dots`]).
#[inline]
fn each_dot<'a>(
    column: impl Fn(usize) -> &'a [f64],
    range: std::ops::Range<usize>,
    f: &[f64],
    mut each: impl FnMut(usize, f64),
) {
    let (mut i, end) = (range.start, range.end);
    while end - i >= 4 {
        let sums = dots([column(i), column(i + 1), column(i + 2), column(i + 3)], f);
        sums.into_iter().enumerate().for_each(|(k, x)| each(i + k, x));
        i += 4;
    }
    while end - i >= 2 {
        let sums = dots([column(i), column(i + 1)], f);
        sums.into_iter().enumerate().for_each(|(k, x)| each(i + k, x));
        i += 2;
    }
    if i < end {
        each(i, dots([column(i)], f)[0]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dense and the sparse form of one full G give the same products (to rounding: the sums
    /// run in another order).
    #[test]
    fn dense_and_sparse_maps_agree() {
        let (size, dampers) = (3, 19);
        let rows: Vec<Vec<(usize, f64)>> = (0..dampers)
            .map(|d| (0..size).map(|i| (i, ((d * 7 + i * 3) % 11) as f64 - 5.0 + 0.25 * i as f64)).collect())
            .collect();
        let dense = DamperMap::new(rows.clone(), size);
        assert!(matches!(dense, DamperMap::Dense { .. }));
        let sparse = DamperMap::Sparse(rows);
        let s = [0.3, -1.2, 2.5];
        let (mut a, mut b) = (vec![0.0; dampers], vec![0.0; dampers]);
        dense.velocities(&s, &mut a);
        sparse.velocities(&s, &mut b);
        let close = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(x, y)| (x - y).abs() <= 1e-13 * (1.0 + y.abs()));
        assert!(close(&a, &b), "{a:?} against {b:?}");
        let forces: Vec<f64> = (0..dampers).map(|d| (d as f64 - 3.0) * 0.7).collect();
        let (mut a, mut b) = (vec![1.0; size], vec![1.0; size]);
        dense.add_transposed(&forces, &mut a);
        sparse.add_transposed(&forces, &mut b);
        assert!(close(&a, &b), "{a:?} against {b:?}");
        let weights: Vec<f64> = (0..dampers).map(|d| 1.0 + d as f64).collect();
        let (mut a, mut b) = (vec![0.5; size * size], vec![0.5; size * size]);
        dense.add_weighted_gram(&weights, &mut a, &mut Vec::new());
        sparse.add_weighted_gram(&weights, &mut b, &mut Vec::new());
        assert!(close(&a, &b), "{a:?} against {b:?}");
        let (mut a, mut b) = (vec![0.0; size], vec![0.0; size]);
        dense.add_row(4, 2.0, &mut a);
        sparse.add_row(4, 2.0, &mut b);
        assert_eq!(a, b);
    }

    #[test]
    fn rows_with_gaps_stay_sparse() {
        let map = DamperMap::new(vec![vec![(0, 1.0), (2, -1.0)], vec![(1, 1.0), (2, 0.5)]], 3);
        assert!(matches!(map, DamperMap::Sparse(_)));
        assert_eq!(map.first_index(1, 3), 1);
    }
}
