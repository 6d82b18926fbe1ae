//! Nonlinear viscous dampers (Eq. 12) and the implicit solve of their forces within a time step.
//!
//! A damper on a brace of angle θ between floors j−1 and j has axial velocity
//! v = cos θ·(u̇_j − u̇_{j−1}) and axial force F = c·sgn(v)|v|^α; its horizontal component cos θ·F
//! acts equal and opposite on the two floors and is subtracted from the loads (a restoring force).
//!
//! Both reference integrators lead, at every step, to the same problem in the new velocities s:
//! s = a − W Gᵀ F(G s), with W symmetric positive definite and G mapping s to damper velocities.
//! That is the stationarity condition of the strictly convex
//! J(s) = ½ (s − a)ᵀ W⁻¹ (s − a) + Σ_d c_d/(1+α) |G_d s|^{1+α},
//! so Newton's method with a backtracking line search on J converges from any start. The infinite
//! slope of |v|^α at v = 0 (α < 1) only enters the Hessian, where it is capped; the residual that
//! decides convergence is exact.

use super::factored::{Curvature, FactoredModel};
use super::power::{power, sign_power};
use crate::error::{Error, Result};
use crate::linalg::{dot, multiply_into};
use crate::structure::Structure;
use crate::structure::spatial::{Dof, SpatialStructure, dof};
use faer::MatRef;

const MAX_NEWTON_ITERATIONS: usize = 100;
/// Converged when no velocity moves by more than this fraction of the largest one (10⁻¹¹ m/s for
/// this building's 10⁻² m/s), far below anything that shows in a response.
const STEP_TOLERANCE: f64 = 1e-9;
/// In the Hessian model, damper velocities below this fraction of the step tolerance count as this,
/// which keeps |v|^{α−1} finite. An iterate inside the floor then moves by less than the tolerance,
/// so the solve ends; the solution itself is unaffected because the gradient is exact.
const HESSIAN_FLOOR_FRACTION: f64 = 1e-2;

/// The dampers of one structure with one coefficient per group.
#[derive(Debug, Clone)]
pub struct Dampers {
    /// Coefficient c of each damper (N·(s/m)^α).
    pub coefficients: Vec<f64>,
    /// Exponent α of the law.
    pub exponent: f64,
    /// Each damper's axial velocity as a combination of the velocities of the degrees of freedom
    /// (one per floor in a plane frame, [`dof`] in a three-dimensional building): (index, weight).
    pub floor_weights: Vec<Vec<(usize, f64)>>,
}

impl Dampers {
    /// `group_coefficients[g]` is the coefficient of every damper in group g.
    pub fn new(structure: &Structure, group_coefficients: &[f64], exponent: f64) -> Result<Self> {
        let rows = structure.dampers.iter().map(|d| {
            let mut row = vec![(d.upper_floor, d.cos_angle)];
            if let Some(lower) = d.lower_floor {
                row.push((lower, -d.cos_angle));
            }
            (d.group, row)
        });
        Dampers::from_rows(rows, structure.damper_groups(), group_coefficients, exponent)
    }

    /// The dampers of a three-dimensional building: each one's axial velocity is cos θ times the
    /// relative velocity of its two floors at its point of the plan, along its direction, so its
    /// row weighs both floors' sway and twist (degrees of freedom as [`dof`]).
    pub fn spatial(structure: &SpatialStructure, group_coefficients: &[f64], exponent: f64) -> Result<Self> {
        let rows = structure.dampers.iter().map(|d| {
            let placement = &d.placement;
            let floor_row = |floor: usize, sign: f64| {
                let weights = d.weights(structure.centres_of_mass[floor]);
                [Dof::X, Dof::Y, Dof::Rotation]
                    .into_iter()
                    .filter(move |&k| weights[k as usize] != 0.0)
                    .map(move |k| (dof(floor, k), sign * placement.cos_angle * weights[k as usize]))
            };
            let mut row: Vec<(usize, f64)> = floor_row(placement.upper_floor, 1.0).collect();
            if let Some(lower) = placement.lower_floor {
                row.extend(floor_row(lower, -1.0));
            }
            (placement.group, row)
        });
        Dampers::from_rows(rows, structure.damper_groups(), group_coefficients, exponent)
    }

    /// The dampers of `rows` (each damper's group and its velocity row), the law checked first.
    fn from_rows(
        rows: impl Iterator<Item = (usize, Vec<(usize, f64)>)>,
        groups: usize,
        group_coefficients: &[f64],
        exponent: f64,
    ) -> Result<Self> {
        check_law(groups, group_coefficients, exponent)?;
        let (coefficients, floor_weights) = rows.map(|(group, row)| (group_coefficients[group], row)).unzip();
        Ok(Dampers { coefficients, exponent, floor_weights })
    }

    /// The law's exponent lies in (0, 2]: what a study checks before any sample's coefficients.
    pub fn check_exponent(exponent: f64) -> Result<()> {
        if !(exponent.is_finite() && exponent > 0.0 && exponent <= 2.0) {
            return Err(Error::invalid("damper_exponent", format!("must lie in (0, 2], got {exponent}")));
        }
        Ok(())
    }

    /// Number of dampers.
    pub fn len(&self) -> usize {
        self.coefficients.len()
    }

    /// Whether the structure has no dampers.
    pub fn is_empty(&self) -> bool {
        self.coefficients.is_empty()
    }

    /// Axial force of damper d at axial velocity v, by the power the solve uses.
    pub fn force(&self, d: usize, v: f64) -> f64 {
        self.coefficients[d] * sign_power(v, self.exponent)
    }

    /// Damper velocities as combinations of modal velocities: G = B Φ.
    pub fn modal_map(&self, shapes: MatRef<'_, f64>) -> Vec<Vec<(usize, f64)>> {
        self.floor_weights
            .iter()
            .map(|row| {
                (0..shapes.ncols()).map(|m| (m, row.iter().map(|&(floor, w)| w * shapes[(floor, m)]).sum())).collect()
            })
            .collect()
    }
}

/// The law's exponent lies in (0, 2] and each of the `groups` coefficients is finite and ≥ 0.
fn check_law(groups: usize, group_coefficients: &[f64], exponent: f64) -> Result<()> {
    Dampers::check_exponent(exponent)?;
    if group_coefficients.len() != groups {
        return Err(Error::invalid(
            "damper coefficients",
            format!("{groups} groups need {groups} coefficients, got {}", group_coefficients.len()),
        ));
    }
    for (g, &c) in group_coefficients.iter().enumerate() {
        if !(c.is_finite() && c >= 0.0) {
            return Err(Error::invalid(
                format!("inputs.damper_c{}", g + 1),
                format!("must be finite and ≥ 0, got {c}"),
            ));
        }
    }
    Ok(())
}

/// out = x − y.
fn subtract_into(out: &mut [f64], x: &[f64], y: &[f64]) {
    for ((d, x), y) in out.iter_mut().zip(x).zip(y) {
        *d = x - y;
    }
}

/// Newton solver for s = a − W Gᵀ F(G s) in the new velocities, with preallocated work space
/// reused every step.
#[derive(Debug, Clone)]
pub struct ImplicitDamperSolve {
    coefficients: Vec<f64>,
    exponent: f64,
    /// W⁻¹ + Gᵀ diag(w) G, kept factored across steps; it holds W⁻¹ (row-major, size×size) as its
    /// fixed part and G as its rows (damper d's velocity is Σ weight·s[index]).
    model: FactoredModel,
    gradient: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<f64>,
    /// W⁻¹(s − a) at the current iterate, and W⁻¹ times the step.
    residual: Vec<f64>,
    w_step: Vec<f64>,
    /// Damper velocities G s at the current iterate and at the trial, with |v|^α of each: a power
    /// is the expensive part of an iteration, so each is computed once.
    velocities: Vec<f64>,
    powers: Vec<f64>,
    trial_velocities: Vec<f64>,
    trial_powers: Vec<f64>,
}

impl ImplicitDamperSolve {
    /// A solver for W⁻¹ = `w_inverse` (row-major, size×size) and the damper velocities G = `map`
    /// (per damper, (index, weight) pairs), with the coefficients and exponent of `dampers`.
    pub fn new(w_inverse: Vec<f64>, map: Vec<Vec<(usize, f64)>>, dampers: &Dampers) -> Self {
        let size = (w_inverse.len() as f64).sqrt().round() as usize;
        let dampers_count = dampers.len();
        ImplicitDamperSolve {
            model: FactoredModel::new(w_inverse, map),
            coefficients: dampers.coefficients.clone(),
            exponent: dampers.exponent,
            gradient: vec![0.0; size],
            step: vec![0.0; size],
            trial: vec![0.0; size],
            residual: vec![0.0; size],
            w_step: vec![0.0; size],
            velocities: vec![0.0; dampers_count],
            powers: vec![0.0; dampers_count],
            trial_velocities: vec![0.0; dampers_count],
            trial_powers: vec![0.0; dampers_count],
        }
    }

    /// Velocities G s and their powers |v|^α, the powers by [`power`] in a pass of their own so
    /// that it vectorises (`powf` was a fifth of a calibration's time, in these solves).
    fn evaluate(&self, s: &[f64], velocities: &mut [f64], powers: &mut [f64]) {
        self.model.map().velocities(s, velocities);
        for (p, v) in powers.iter_mut().zip(velocities.iter()) {
            *p = power(v.abs(), self.exponent);
        }
    }

    /// The current iterate's velocities and powers, at `s`.
    fn evaluate_iterate(&mut self, s: &[f64]) {
        let (mut velocities, mut powers) = (std::mem::take(&mut self.velocities), std::mem::take(&mut self.powers));
        self.evaluate(s, &mut velocities, &mut powers);
        (self.velocities, self.powers) = (velocities, powers);
    }

    /// Σ_d c_d/(1+α)·|v_d|^{1+α}, from the velocities and their powers |v|^α.
    fn dissipation(&self, velocities: &[f64], powers: &[f64]) -> f64 {
        let p = 1.0 + self.exponent;
        velocities.iter().zip(powers).zip(&self.coefficients).map(|((v, pw), c)| c / p * v.abs() * pw).sum()
    }

    /// The axial forces and the gradient W⁻¹(s − a) + Gᵀ F at the current iterate.
    fn gradient_and_forces(&mut self, forces: &mut [f64]) {
        self.forces_at_iterate(forces);
        self.gradient.copy_from_slice(&self.residual);
        self.model.map().add_transposed(forces, &mut self.gradient);
    }

    /// The model's damper weights w_d = c·|v|^{α−1}, times α for the tangent; velocities below
    /// `floor` count as the floor, which keeps the weight finite.
    fn curvature_weights(&mut self, curvature: Curvature, floor: f64) {
        let alpha = self.exponent;
        let factor = if curvature == Curvature::Tangent { alpha } else { 1.0 };
        // A select, not a branch, so that the pass vectorises.
        let floor_slope = floor.powf(alpha - 1.0);
        let weights = self.model.weights.iter_mut().zip(&self.coefficients);
        for ((w, c), (v, p)) in weights.zip(self.velocities.iter().zip(&self.powers)) {
            let magnitude = v.abs();
            let slope = if magnitude > floor { p / magnitude } else { floor_slope };
            *w = c * factor * slope;
        }
    }

    /// step = −H⁻¹ g with the model brought up to date for `curvature`.
    fn model_step(&mut self, curvature: Curvature, floor: f64) -> Result<()> {
        self.curvature_weights(curvature, floor);
        self.model.refresh(curvature)?;
        self.model.newton_step(&self.gradient, &mut self.step);
        Ok(())
    }

    /// The axial forces at the current iterate's velocities.
    fn forces_at_iterate(&self, forces: &mut [f64]) {
        for (d, f) in forces.iter_mut().enumerate() {
            *f = self.coefficients[d] * self.velocities[d].signum() * self.powers[d];
        }
    }

    /// Moves the iterate by the step: s, W⁻¹(s − a) and, unless `known` (the trial's are), the
    /// damper velocities and powers.
    fn advance(&mut self, s: &mut [f64], known: bool) {
        s.iter_mut().zip(&self.step).for_each(|(x, d)| *x += d);
        self.residual.iter_mut().zip(&self.w_step).for_each(|(r, d)| *r += d);
        if known {
            std::mem::swap(&mut self.velocities, &mut self.trial_velocities);
            std::mem::swap(&mut self.powers, &mut self.trial_powers);
        } else {
            self.evaluate_iterate(s);
        }
    }

    /// out = Gᵀ `forces`: the damper forces on the unknowns (the modes of a reduced model).
    pub fn generalized_forces(&self, forces: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|x| *x = 0.0);
        self.model.map().add_transposed(forces, out);
    }

    /// Solves for the new velocities. `s` holds the initial guess on entry and the solution on exit;
    /// `forces` receives the axial damper forces at the solution. Returns the iterations used.
    ///
    /// Each iteration tries Newton's step and keeps it if J falls enough (Armijo). Otherwise it takes
    /// the majorize-minimize step instead: |v|^{1+α} is concave in v², so the quadratic with the
    /// secant curvature c|v|^{α−1} (or more) lies above J and touches it at s, and its minimiser
    /// lowers J without a line search. That is what converges where a damper comes to rest at the
    /// solution, where Newton overshoots by the factor 1 − 1/α.
    ///
    /// J's change along a step p is computed directly, pᵀW⁻¹(s − a) + ½pᵀW⁻¹p plus the change of the
    /// dissipation: no cancellation between two nearly equal values of J. W⁻¹(s − a) is carried
    /// from iterate to iterate, one product with W⁻¹ per iteration instead of two (the full-order
    /// integration of a 300 s storm: 7.4·10⁹ instructions instead of 8.5·10⁹). Its rounding, about
    /// 10⁻¹⁶ of the distance travelled, stays below the tolerance unless the start is some 10⁷
    /// times farther from the solution than the velocities' own size; the integrators start from
    /// the previous step's correction.
    pub fn solve(&mut self, a: &[f64], s: &mut [f64], forces: &mut [f64]) -> Result<usize> {
        self.evaluate_iterate(s);
        subtract_into(&mut self.w_step, s, a);
        multiply_into(&mut self.residual, self.model.fixed(), &self.w_step);
        for iteration in 0..MAX_NEWTON_ITERATIONS {
            let scale = s.iter().chain(a).fold(0.0f64, |m, x| m.max(x.abs()));
            let tolerance = STEP_TOLERANCE * scale + f64::MIN_POSITIVE;
            let floor = HESSIAN_FLOOR_FRACTION * tolerance;
            self.gradient_and_forces(forces);
            self.model_step(Curvature::Tangent, floor)?;
            let largest_step = self.step.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if largest_step <= tolerance {
                s.iter_mut().zip(&self.step).for_each(|(x, d)| *x += d);
                self.evaluate_iterate(s);
                self.forces_at_iterate(forces);
                return Ok(iteration + 1);
            }
            multiply_into(&mut self.w_step, self.model.fixed(), &self.step);
            for ((trial, x), step) in self.trial.iter_mut().zip(s.iter()).zip(&self.step) {
                *trial = x + step;
            }
            let (mut velocities, mut powers) =
                (std::mem::take(&mut self.trial_velocities), std::mem::take(&mut self.trial_powers));
            self.evaluate(&self.trial, &mut velocities, &mut powers);
            let dissipation_change =
                self.dissipation(&velocities, &powers) - self.dissipation(&self.velocities, &self.powers);
            (self.trial_velocities, self.trial_powers) = (velocities, powers);
            let change = dot(&self.step, &self.residual) + 0.5 * dot(&self.step, &self.w_step) + dissipation_change;
            let slope = dot(&self.gradient, &self.step);
            if change <= 1e-4 * slope {
                self.advance(s, true);
            } else {
                self.model_step(Curvature::Majorizing, floor)?;
                multiply_into(&mut self.w_step, self.model.fixed(), &self.step);
                self.advance(s, false);
            }
        }
        Err(Error::Numerical(format!("the damper forces did not converge in {MAX_NEWTON_ITERATIONS} iterations")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The carried-factor test's problem: a chain of `n` floors with a damper (cos θ = 0.8, c = 40,
    /// α = 0.38) in every storey, and a dense, diagonally dominant W⁻¹.
    fn test_chain(n: usize) -> (Dampers, Vec<f64>) {
        let floor_weights: Vec<Vec<(usize, f64)>> =
            (0..n).map(|j| if j == 0 { vec![(0, 0.8)] } else { vec![(j, 0.8), (j - 1, -0.8)] }).collect();
        let w_inverse: Vec<f64> = (0..n * n)
            .map(|k| {
                let (i, j) = ((k / n) as f64, (k % n) as f64);
                0.5 / (1.0 + (i - j).powi(2)) + if i == j { 100.0 } else { 0.0 }
            })
            .collect();
        (Dampers { coefficients: vec![40.0; n], exponent: 0.38, floor_weights }, w_inverse)
    }

    /// The chain's a at step `step` of a slowly turning load, which brings dampers to rest in turn.
    fn test_chain_load(n: usize, step: usize) -> Vec<f64> {
        let t = step as f64 * 0.05;
        (0..n).map(|j| 0.01 * (t + 0.3 * j as f64).sin() * (1.0 + j as f64) / n as f64).collect()
    }

    fn single(c: f64, alpha: f64) -> Dampers {
        Dampers { coefficients: vec![c], exponent: alpha, floor_weights: vec![vec![(0, 1.0)]] }
    }

    /// One unknown, one damper: s + w c sgn(s)|s|^α = a, a monotone scalar equation whose root
    /// bisection finds independently. Starts on the wrong side, far away and at zero, a stiff damper
    /// (w c large) and a root at zero (where |v|^α has its infinite slope) all converge, to the
    /// solver's tolerance of 10⁻⁹ of the largest velocity (with a factor 2 for its estimate of the
    /// error).
    #[test]
    fn scalar_problem_is_solved_from_any_start() {
        for (a, w, c) in [(1.0, 0.1, 2.0), (-0.3, 1.0, 50.0), (1e-6, 1.0, 1e4), (0.0, 1.0, 1.0), (2.0, 1e-8, 1e5)] {
            let dampers = single(c, 0.38);
            let residual = |s: f64| s + w * dampers.force(0, s) - a;
            let (mut lo, mut hi) = (-10.0, 10.0);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if residual(mid) > 0.0 { hi = mid } else { lo = mid }
            }
            let root = 0.5 * (lo + hi);
            let mut solver = ImplicitDamperSolve::new(vec![1.0 / w], vec![vec![(0, 1.0)]], &dampers);
            for start in [0.0, -5.0, 5.0, a, -1e3, 1e3] {
                let mut s = [start];
                let mut f = [0.0];
                solver.solve(&[a], &mut s, &mut f).unwrap();
                assert!(
                    (s[0] - root).abs() <= 2.0 * STEP_TOLERANCE * a.abs().max(root.abs()) + 1e-14,
                    "a={a} w={w} c={c} start={start}: {} vs {root}",
                    s[0]
                );
            }
        }
    }

    /// Linear dampers (α = 1) make the problem linear: s = (W⁻¹ + Gᵀ c G)⁻¹ W⁻¹ a.
    #[test]
    fn linear_dampers_give_the_linear_solution() {
        let dampers = Dampers {
            coefficients: vec![3.0, 1.5],
            exponent: 1.0,
            floor_weights: vec![vec![(0, 1.0)], vec![(1, 0.8), (0, -0.8)]],
        };
        let map = dampers.floor_weights.clone();
        let w_inverse = vec![2.0, 0.3, 0.3, 1.0];
        let mut solver = ImplicitDamperSolve::new(w_inverse, map, &dampers);
        let a = [0.7, -0.4];
        let mut s = [0.0, 0.0];
        let mut f = [0.0, 0.0];
        solver.solve(&a, &mut s, &mut f).unwrap();
        // Assemble (W⁻¹ + Gᵀ C G) and W⁻¹ a by hand.
        let h = [[2.0 + 3.0 + 1.5 * 0.64, 0.3 - 1.5 * 0.64], [0.3 - 1.5 * 0.64, 1.0 + 1.5 * 0.64]];
        let r = [2.0 * 0.7 + 0.3 * -0.4, 0.3 * 0.7 + 1.0 * -0.4];
        let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
        let expected = [(h[1][1] * r[0] - h[0][1] * r[1]) / det, (h[0][0] * r[1] - h[1][0] * r[0]) / det];
        assert!((s[0] - expected[0]).abs() < 1e-12 && (s[1] - expected[1]).abs() < 1e-12, "{s:?} vs {expected:?}");
    }

    /// A chain of 20 floors with a damper in every storey and a dense W⁻¹, solved at a sequence of
    /// slowly turning loads as an integrator would, with the factor carried from call to call and
    /// changed damper by damper: every solution equals a fresh solver's to the tolerance and
    /// satisfies the stationarity condition W⁻¹(s − a) + Gᵀ F(G s) = 0 to what that tolerance allows.
    #[test]
    fn factor_carried_across_steps_gives_the_fresh_solution() {
        let n = 20;
        let (dampers, w_inverse) = test_chain(n);
        let floor_weights = dampers.floor_weights.clone();
        let mut carried = ImplicitDamperSolve::new(w_inverse.clone(), floor_weights.clone(), &dampers);
        let mut s = vec![0.0; n];
        let mut forces = vec![0.0; n];
        let mut rank_one_changes_seen = false;
        for step in 0..200 {
            let a = test_chain_load(n, step);
            carried.solve(&a, &mut s, &mut forces).unwrap();
            rank_one_changes_seen |= carried.model.rank_one_changes > 0;
            let mut fresh = ImplicitDamperSolve::new(w_inverse.clone(), floor_weights.clone(), &dampers);
            let (mut expected, mut expected_forces) = (a.clone(), vec![0.0; n]);
            fresh.solve(&a, &mut expected, &mut expected_forces).unwrap();
            let scale = a.iter().chain(&s).fold(0.0f64, |m, x| m.max(x.abs()));
            for j in 0..n {
                assert!(
                    (s[j] - expected[j]).abs() <= 4.0 * STEP_TOLERANCE * scale,
                    "step {step}, floor {j}: {} vs {}, tolerance {}",
                    s[j],
                    expected[j],
                    STEP_TOLERANCE * scale
                );
            }
            let mut stationarity = vec![0.0; n];
            let difference: Vec<f64> = s.iter().zip(&a).map(|(x, y)| x - y).collect();
            multiply_into(&mut stationarity, &w_inverse, &difference);
            for (row, f) in floor_weights.iter().zip(&forces) {
                for &(i, w) in row {
                    stationarity[i] += w * f;
                }
            }
            // An error e in s (|e| ≤ 4 tolerances) moves W⁻¹(s − a) by at most its row sum times e,
            // and a force by at most c·|G e|^α, however close to rest the damper is (Hölder, not
            // Lipschitz, at v = 0); each floor feels two dampers.
            let error = 4.0 * STEP_TOLERANCE * scale;
            let slack =
                w_inverse.chunks_exact(n).map(|row| row.iter().map(|x| x.abs()).sum::<f64>()).fold(0.0, f64::max)
                    * error
                    + 2.0 * 0.8 * 40.0 * (1.6 * error).powf(0.38);
            assert!(stationarity.iter().all(|g| g.abs() <= slack), "step {step}: {stationarity:?}");
        }
        assert!(rank_one_changes_seen, "the factor was never changed in place");
    }
}
