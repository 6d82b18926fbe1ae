//! The implicit damper solve in the forces instead of the velocities.
//!
//! Where a damper comes to rest within a step, |v|^α (α < 1) has an infinite slope at v = 0 and
//! Newton's step in the velocities overshoots; the iterates then crawl (on a full-order storm, 5.7
//! iterations per step on average and over 19 in some steps). The law's inverse,
//! v = ψ(F) = sgn F·(|F|/c)^{1/α}, is smooth there: ψ'(0) = 0. Eliminating s = a − W GᵀF, the
//! forces solve ψ(F) = G(a − W GᵀF), the stationarity condition of the strictly convex dual
//!
//!   D(F) = ½FᵀQF − Fᵀ(G a) + Σ_d Ψ_d(F_d),   Q = G W Gᵀ,   Ψ_d(F) = α/(1+α)·|F|·|ψ_d(F)|,
//!
//! whose Hessian Q + diag ψ'(F) stays bounded where a damper is at rest. It needs Q positive
//! definite, so no more dampers than unknowns and independent rows of G (the full-order model, one
//! damper per storey), every damper active, and α < 1 (for α > 1 it is ψ' that is unbounded, and the
//! velocities are the better unknowns).

use super::damper::Dampers;
use super::factored::{Curvature, FactoredModel};
use crate::error::{Error, Result};
use crate::linalg::{cholesky, cholesky_solve, dot, multiply_into};

/// Q's smallest pivot, squared, must exceed this fraction of its largest diagonal entry: below it
/// the damper rows are too nearly dependent for the dual to be well posed.
const PIVOT_FRACTION: f64 = 1e-12;

/// The band of the force solve's factored weights (see [`FactoredModel`]). Tighter than the
/// velocity solve's: once the step is small, the iterates converge at a rate of about band − 1.
/// Per step of the full-order storm, starting from the previous forces, the band 1.25 took 9.8
/// Newton iterations, 1.1 took 6.9, 1.03 took 5.1, exact Newton 4.1 (but a factorisation each);
/// from the extrapolated forces the integrator passes, 1.05 takes 5.0 iterations, 0.27
/// factorisations and 8.9 rank-one changes.
const WEIGHT_BAND: f64 = 1.05;

/// Relative rounding of a change of D formed from its terms (about 4500 units of the last place,
/// for sums of tens of terms).
const ROUNDING: f64 = 1e-12;

/// Newton solver for the damper forces of a step, with its work space.
#[derive(Debug, Clone)]
pub struct ForceDamperSolve {
    /// W, row-major n×n.
    w: Vec<f64>,
    /// G as sparse rows, as in [`super::ImplicitDamperSolve`].
    map: Vec<Vec<(usize, f64)>>,
    coefficients: Vec<f64>,
    exponent: f64,
    /// Q = G W Gᵀ, row-major.
    q: Vec<f64>,
    /// Q + diag ψ'(F), kept factored across steps.
    model: FactoredModel,
    /// G a: the damper velocities the step would have without damper forces.
    free_velocities: Vec<f64>,
    /// QF − G a = −G s(F) at the iterate: minus the damper velocities the forces leave.
    residual: Vec<f64>,
    gradient: Vec<f64>,
    step: Vec<f64>,
    q_step: Vec<f64>,
    trial: Vec<f64>,
    /// The law's speed (|F|/c)^{1/α} at the iterate and at the trial: a power is the expensive part
    /// of an iteration, so each is computed once.
    speeds: Vec<f64>,
    trial_speeds: Vec<f64>,
    /// Gᵀ F.
    push: Vec<f64>,
}

impl ForceDamperSolve {
    /// The solver for s = a − W Gᵀ F(G s) given W⁻¹, or `None` where the dual does not apply (see
    /// the module's documentation).
    pub fn new(w_inverse: &[f64], map: &[Vec<(usize, f64)>], dampers: &Dampers) -> Option<Self> {
        let n = (w_inverse.len() as f64).sqrt().round() as usize;
        let count = dampers.len();
        let active = dampers.coefficients.iter().all(|&c| c > 0.0 && c.is_finite());
        if dampers.exponent >= 1.0 || count == 0 || count > n || !active {
            return None;
        }
        let mut factor = w_inverse.to_vec();
        if !cholesky(&mut factor, n) {
            return None;
        }
        let mut w = vec![0.0; n * n];
        let mut column = vec![0.0; n];
        for j in 0..n {
            column.iter_mut().enumerate().for_each(|(i, x)| *x = if i == j { 1.0 } else { 0.0 });
            cholesky_solve(&factor, n, &mut column);
            (0..n).for_each(|i| w[i * n + j] = column[i]);
        }
        // W G_eᵀ for each damper e, then Q_de = G_d·(W G_eᵀ), symmetrised against rounding.
        let w_g: Vec<Vec<f64>> =
            map.iter().map(|row| (0..n).map(|i| row.iter().map(|&(j, g)| w[i * n + j] * g).sum()).collect()).collect();
        let product = |d: usize, e: usize| -> f64 { map[d].iter().map(|&(i, g)| g * w_g[e][i]).sum() };
        let q: Vec<f64> = (0..count * count)
            .map(|k| {
                let (d, e) = (k / count, k % count);
                0.5 * (product(d, e) + product(e, d))
            })
            .collect();
        let mut check = q.clone();
        let largest = (0..count).map(|d| q[d * count + d]).fold(0.0, f64::max);
        // The factor's diagonal holds the reciprocal pivots.
        if !cholesky(&mut check, count) || (0..count).any(|d| check[d * count + d].powi(-2) < PIVOT_FRACTION * largest)
        {
            return None;
        }
        let unit_rows = (0..count).map(|d| vec![(d, 1.0)]).collect();
        Some(ForceDamperSolve {
            w,
            map: map.to_vec(),
            coefficients: dampers.coefficients.clone(),
            exponent: dampers.exponent,
            model: FactoredModel::new(q.clone(), unit_rows, WEIGHT_BAND),
            q,
            free_velocities: vec![0.0; count],
            residual: vec![0.0; count],
            gradient: vec![0.0; count],
            step: vec![0.0; count],
            q_step: vec![0.0; count],
            trial: vec![0.0; count],
            speeds: vec![0.0; count],
            trial_speeds: vec![0.0; count],
            push: vec![0.0; n],
        })
    }

    /// The law's speeds (|F|/c)^{1/α}.
    fn speeds_into(&self, forces: &[f64], speeds: &mut [f64]) {
        let inverse = 1.0 / self.exponent;
        for ((speed, f), c) in speeds.iter_mut().zip(forces).zip(&self.coefficients) {
            *speed = (f.abs() / c).powf(inverse);
        }
    }

    /// Σ_d Ψ_d(F_d) = Σ α/(1+α)·|F|·speed.
    fn potential(&self, forces: &[f64], speeds: &[f64]) -> f64 {
        let share = self.exponent / (1.0 + self.exponent);
        share * forces.iter().zip(speeds).map(|(f, v)| f.abs() * v).sum::<f64>()
    }

    /// Solves for the forces, starting from those in `forces` (the previous step's are a good
    /// guess), and writes the new velocities s = a − W GᵀF into `s`. Returns the iterations used.
    ///
    /// Newton's step on D with a backtracking (Armijo) line search, which D's convexity makes
    /// globally convergent. Converged when the step moves no damper velocity by more than
    /// [`super::damper::STEP_TOLERANCE`] of the largest, as in the velocity solve.
    pub fn solve(&mut self, a: &[f64], s: &mut [f64], forces: &mut [f64]) -> Result<usize> {
        for (v, row) in self.free_velocities.iter_mut().zip(&self.map) {
            *v = row.iter().map(|&(i, g)| g * a[i]).sum();
        }
        let mut speeds = std::mem::take(&mut self.speeds);
        self.speeds_into(forces, &mut speeds);
        self.speeds = speeds;
        for iteration in 0..super::damper::MAX_NEWTON_ITERATIONS {
            // Formed afresh at every iterate: carried from one to the next, it would keep the
            // rounding of a start far from the solution.
            multiply_into(&mut self.residual, &self.q, forces);
            self.residual.iter_mut().zip(&self.free_velocities).for_each(|(r, v)| *r -= v);
            let scale = self.free_velocities.iter().chain(&self.residual).fold(0.0f64, |m, x| m.max(x.abs()));
            let tolerance = super::damper::STEP_TOLERANCE * scale + f64::MIN_POSITIVE;
            for (d, &f) in forces.iter().enumerate() {
                let speed = self.speeds[d];
                self.gradient[d] = self.residual[d] + f.signum() * speed;
                self.model.weights[d] = if f == 0.0 { 0.0 } else { speed / (self.exponent * f.abs()) };
            }
            self.model.refresh(Curvature::Tangent)?;
            self.model.newton_step(&self.gradient, &mut self.step);
            multiply_into(&mut self.q_step, &self.q, &self.step);
            let largest = self.q_step.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if largest <= tolerance {
                forces.iter_mut().zip(&self.step).for_each(|(f, d)| *f += d);
                self.velocities_into(a, forces, s);
                return Ok(iteration + 1);
            }
            let slope = dot(&self.gradient, &self.step);
            let (linear, quadratic) = (dot(&self.step, &self.residual), dot(&self.step, &self.q_step));
            let before = self.potential(forces, &self.speeds);
            let mut length = 1.0;
            loop {
                for ((t, f), d) in self.trial.iter_mut().zip(forces.iter()).zip(&self.step) {
                    *t = f + length * d;
                }
                let mut trial_speeds = std::mem::take(&mut self.trial_speeds);
                self.speeds_into(&self.trial, &mut trial_speeds);
                self.trial_speeds = trial_speeds;
                let after = self.potential(&self.trial, &self.trial_speeds);
                let (first, second) = (length * linear, 0.5 * length * length * quadratic);
                let change = first + second + (after - before);
                // Near the solution D changes by less than the rounding of its terms; there the
                // test cannot tell, and Newton's step (accurate there) is taken.
                let rounding = ROUNDING * (before.abs() + after.abs() + first.abs() + second.abs());
                if change <= 1e-4 * length * slope || change.abs() <= rounding {
                    break;
                }
                length *= 0.5;
                if length < 1e-12 {
                    return Err(Error::Numerical("the damper force line search found no descent".into()));
                }
            }
            forces.copy_from_slice(&self.trial);
            std::mem::swap(&mut self.speeds, &mut self.trial_speeds);
        }
        Err(Error::Numerical(format!(
            "the damper forces did not converge in {} iterations",
            super::damper::MAX_NEWTON_ITERATIONS
        )))
    }

    /// s = a − W GᵀF.
    fn velocities_into(&mut self, a: &[f64], forces: &[f64], s: &mut [f64]) {
        self.push.iter_mut().for_each(|x| *x = 0.0);
        for (row, f) in self.map.iter().zip(forces) {
            for &(i, g) in row {
                self.push[i] += g * f;
            }
        }
        multiply_into(s, &self.w, &self.push);
        s.iter_mut().zip(a).for_each(|(x, a)| *x = a - *x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::ImplicitDamperSolve;
    use crate::dynamics::damper::{STEP_TOLERANCE, test_chain, test_chain_load};

    /// One unknown, one damper: s + w·c·sgn(s)|s|^α = a, solved in the force from several starts,
    /// against bisection of the scalar equation (as the velocity solve's own test does).
    #[test]
    fn scalar_problem_is_solved_in_the_force() {
        for (a, w, c) in [(1.0, 0.1, 2.0), (-0.3, 1.0, 50.0), (1e-6, 1.0, 1e4), (0.0, 1.0, 1.0), (2.0, 1e-8, 1e5)] {
            let dampers = Dampers { coefficients: vec![c], exponent: 0.38, floor_weights: vec![vec![(0, 1.0)]] };
            let residual = |s: f64| s + w * dampers.force(0, s) - a;
            let (mut lo, mut hi) = (-10.0, 10.0);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if residual(mid) > 0.0 { hi = mid } else { lo = mid }
            }
            let root = 0.5 * (lo + hi);
            let mut solver = ForceDamperSolve::new(&[1.0 / w], &[vec![(0, 1.0)]], &dampers).expect("applies");
            for start in [0.0, -5.0 * c, 5.0 * c, a / w] {
                let (mut s, mut f) = ([0.0], [start]);
                solver.solve(&[a], &mut s, &mut f).unwrap();
                assert!(
                    (s[0] - root).abs() <= 2.0 * STEP_TOLERANCE * a.abs().max(root.abs()) + 1e-14,
                    "a={a} w={w} c={c} start={start}: {} vs {root}",
                    s[0]
                );
                assert!((f[0] - dampers.force(0, root)).abs() <= 1e-6 * f[0].abs().max(1e-12), "force {}", f[0]);
            }
        }
    }

    /// The 20-floor chain through 200 steps of a turning load, forces carried from step to step:
    /// the same velocities as the velocity solve, to the tolerance, and fewer iterations where
    /// dampers come to rest.
    #[test]
    fn forces_and_velocities_give_the_same_solution() {
        let n = 20;
        let (dampers, w_inverse) = test_chain(n);
        let map = dampers.floor_weights.clone();
        let mut by_forces = ForceDamperSolve::new(&w_inverse, &map, &dampers).expect("applies");
        let mut by_velocities = ImplicitDamperSolve::new(w_inverse.clone(), map.clone(), &dampers);
        let (mut s, mut forces) = (vec![0.0; n], vec![0.0; n]);
        let (mut expected, mut expected_forces) = (vec![0.0; n], vec![0.0; n]);
        let (mut iterations_by_forces, mut iterations_by_velocities) = (0, 0);
        for step in 0..200 {
            let a = test_chain_load(n, step);
            iterations_by_forces += by_forces.solve(&a, &mut s, &mut forces).unwrap();
            iterations_by_velocities += by_velocities.solve(&a, &mut expected, &mut expected_forces).unwrap();
            let scale = a.iter().chain(&s).fold(0.0f64, |m, x| m.max(x.abs()));
            for j in 0..n {
                assert!(
                    (s[j] - expected[j]).abs() <= 4.0 * STEP_TOLERANCE * scale,
                    "step {step}, floor {j}: {} vs {}",
                    s[j],
                    expected[j]
                );
            }
        }
        assert!(
            iterations_by_forces < iterations_by_velocities,
            "{iterations_by_forces} vs {iterations_by_velocities}"
        );
    }

    /// Where the dual is not well posed the solver declines, and the velocity solve is used.
    #[test]
    fn declines_where_the_dual_does_not_apply() {
        let (dampers, w_inverse) = test_chain(3);
        let map = dampers.floor_weights.clone();
        assert!(ForceDamperSolve::new(&w_inverse, &map, &dampers).is_some());
        let linear = Dampers { exponent: 1.0, ..dampers.clone() };
        assert!(ForceDamperSolve::new(&w_inverse, &map, &linear).is_none(), "α ≥ 1");
        let idle = Dampers { coefficients: vec![40.0, 0.0, 40.0], ..dampers.clone() };
        assert!(ForceDamperSolve::new(&w_inverse, &map, &idle).is_none(), "an inactive damper");
        let twice = Dampers {
            coefficients: vec![40.0; 4],
            floor_weights: vec![map[0].clone(), map[1].clone(), map[2].clone(), map[2].clone()],
            ..dampers.clone()
        };
        assert!(ForceDamperSolve::new(&w_inverse, &twice.floor_weights, &twice).is_none(), "more dampers than floors");
        let dependent = Dampers { floor_weights: vec![map[0].clone(), map[0].clone(), map[2].clone()], ..dampers };
        assert!(
            ForceDamperSolve::new(&w_inverse, &dependent.floor_weights, &dependent).is_none(),
            "two dampers on the same floors"
        );
    }
}
