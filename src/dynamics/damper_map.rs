//! G, the map from the unknowns of a damper solve to the dampers' axial velocities, and the three
//! products a Newton iteration takes of it: G s, Gᵀ f and Gᵀ diag(w) G.
//!
//! A full-order model's rows are sparse (a damper joins two floors: two to six unknowns of the
//! hundreds), a reduced-order model's dense (every mode moves every damper). Dense, G is kept
//! column by column, so that each product is a pass over contiguous dampers that vectorises: the
//! three-dimensional building's 160 dampers on six modes made the row-by-row products, an index
//! and a weight at a time, most of a reduced storm's cost.

use crate::linalg::dot;

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

    /// Multiply-adds of Gᵀ diag(w) G over `size` unknowns.
    pub(super) fn gram_cost(&self, size: usize) -> usize {
        match self {
            DamperMap::Sparse(rows) => rows.iter().map(|row| row.len() * row.len()).sum(),
            DamperMap::Dense { dampers, .. } => dampers * size * (size + 1) / 2,
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
                for (o, column) in out.iter_mut().zip(columns.chunks_exact(*dampers)) {
                    *o += dot(column, forces);
                }
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
                    for j in i..n {
                        let entry = dot(scratch, column(j));
                        matrix[i * n + j] += entry;
                        if j != i {
                            matrix[j * n + i] += entry;
                        }
                    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The dense and the sparse form of one full G give the same products (to rounding: the sums
    /// run in another order).
    #[test]
    fn dense_and_sparse_maps_agree() {
        let (size, dampers) = (3, 7);
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
