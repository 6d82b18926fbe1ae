//! The Newton matrix of a damper solve, H = P + Σ_d w_d r_d r_dᵀ: a fixed symmetric positive
//! definite P and, for each damper, a sparse row r_d and a weight w_d that changes from iteration to
//! iteration. It is kept factored across iterations and time steps and brought up to date damper by
//! damper with rank-one changes of its factor, O(n²) each: between steps most weights barely move,
//! so a 40-floor step usually costs a few such changes rather than an O(n³) factorisation.

use super::damper_map::DamperMap;
use crate::error::{Error, Result};
use crate::linalg::{cholesky, cholesky_rank_one, cholesky_solve};

/// Newton's model may use weights up to this factor away from the wanted ones before they are
/// brought up to date: the step then still contracts the error by about a quarter per iteration, and
/// most steps need no new factorisation (on the full-order storm, 5.7 Newton iterations, 0.6
/// factorisations and 6 rank-one changes per step).
const WEIGHT_BAND: f64 = 1.25;

/// Rank-one changes of the factor since it was last formed, after which it is formed afresh so that
/// the rounding of many downdates cannot accumulate.
const MAX_RANK_ONE_CHANGES: usize = 200;

/// What the factored weights must satisfy against the wanted ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Curvature {
    /// Within [`WEIGHT_BAND`] of them: Newton's step.
    Tangent,
    /// At least them: a model that lies above the objective (majorize-minimize).
    Majorizing,
}

impl Curvature {
    /// Whether the factored weight `have` serves for the wanted `want`.
    fn serves(self, have: f64, want: f64) -> bool {
        match self {
            Curvature::Tangent => have <= want * WEIGHT_BAND && have * WEIGHT_BAND >= want,
            Curvature::Majorizing => have >= want,
        }
    }
}

/// H = P + Σ_d w_d r_d r_dᵀ with its upper Cholesky factor and the work space to change it.
#[derive(Debug, Clone)]
pub(super) struct FactoredModel {
    size: usize,
    /// P, row-major size×size.
    fixed: Vec<f64>,
    /// The rows r_d.
    map: DamperMap,
    /// The lowest index each row touches: rows of the factor above it do not change with w_d.
    first_index: Vec<usize>,
    /// Upper Cholesky factor of P + Σ factor_weights[d] r_d r_dᵀ, when `factored`.
    factor: Vec<f64>,
    factor_weights: Vec<f64>,
    factored: bool,
    pub(super) rank_one_changes: usize,
    /// A rank-one change's vector.
    change: Vec<f64>,
    /// Work space of the dense map's products.
    scratch: Vec<f64>,
    /// Multiply-adds of forming H afresh and factoring it: the rank-one changes that cost less
    /// are made instead. A reduced model's dense G makes the forming, not the factoring, the
    /// larger part (160 dampers on six modes: 3 360 against 72, the forming's counted at a
    /// sixteenth for its vector lanes).
    factorisation_cost: usize,
    /// The weights the caller wants; [`Self::refresh`] brings the factor to them.
    pub(super) weights: Vec<f64>,
    /// The dampers whose factored weight does not serve, found once per refresh.
    stale: Vec<usize>,
}

impl FactoredModel {
    pub(super) fn new(fixed: Vec<f64>, rows: Vec<Vec<(usize, f64)>>) -> Self {
        let size = (fixed.len() as f64).sqrt().round() as usize;
        let map = DamperMap::new(rows, size);
        let factorisation_cost = map.gram_cost(size) + size * size * size / 3;
        let count = map.len();
        FactoredModel {
            size,
            fixed,
            first_index: (0..count).map(|d| map.first_index(d, size)).collect(),
            map,
            factor: vec![0.0; size * size],
            factor_weights: vec![0.0; count],
            factored: false,
            rank_one_changes: 0,
            change: vec![0.0; size],
            scratch: Vec::new(),
            factorisation_cost,
            weights: vec![0.0; count],
            stale: Vec::with_capacity(count),
        }
    }

    /// P.
    pub(super) fn fixed(&self) -> &[f64] {
        &self.fixed
    }

    /// The rows r_d.
    pub(super) fn map(&self) -> &DamperMap {
        &self.map
    }

    /// Brings the factor to `weights` for the dampers whose factored weight does not serve: by
    /// rank-one changes while they cost less than a factorisation, else by factoring afresh.
    pub(super) fn refresh(&mut self, curvature: Curvature) -> Result<()> {
        let n = self.size;
        if self.factored && self.rank_one_changes < MAX_RANK_ONE_CHANGES {
            self.stale.clear();
            let mut cost = 0;
            for (d, (&have, &want)) in self.factor_weights.iter().zip(&self.weights).enumerate() {
                if !curvature.serves(have, want) {
                    self.stale.push(d);
                    cost += 2 * (n - self.first_index[d]).pow(2);
                }
            }
            if cost <= self.factorisation_cost && self.change_stale_weights() {
                return Ok(());
            }
        }
        self.factor.copy_from_slice(&self.fixed);
        self.map.add_weighted_gram(&self.weights, &mut self.factor, &mut self.scratch);
        self.factor_weights.copy_from_slice(&self.weights);
        self.rank_one_changes = 0;
        self.factored = cholesky(&mut self.factor, n);
        if !self.factored {
            return Err(Error::Numerical("the damper Newton system lost positive definiteness".into()));
        }
        Ok(())
    }

    /// The rank-one changes of [`Self::refresh`] for the `stale` dampers; `false` if a downdate
    /// failed.
    fn change_stale_weights(&mut self) -> bool {
        let n = self.size;
        for &d in &self.stale {
            let (have, want) = (self.factor_weights[d], self.weights[d]);
            let first = self.first_index[d];
            let scale = (want - have).abs().sqrt();
            self.change[first..].iter_mut().for_each(|x| *x = 0.0);
            self.map.add_row(d, scale, &mut self.change);
            let sign = if want > have { 1.0 } else { -1.0 };
            if !cholesky_rank_one(&mut self.factor, n, &mut self.change, sign, first) {
                self.factored = false;
                return false;
            }
            self.factor_weights[d] = want;
            self.rank_one_changes += 1;
        }
        true
    }

    /// step = −H⁻¹ gradient with the factored weights.
    pub(super) fn newton_step(&self, gradient: &[f64], step: &mut [f64]) {
        for (x, g) in step.iter_mut().zip(gradient) {
            *x = -g;
        }
        cholesky_solve(&self.factor, self.size, step);
    }
}
