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

use crate::error::{Error, Result};
use crate::linalg::{cholesky, cholesky_solve, dot};
use crate::structure::Structure;
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
    /// Each damper's axial velocity as a combination of floor velocities: (floor, weight) pairs.
    pub floor_weights: Vec<Vec<(usize, f64)>>,
}

impl Dampers {
    /// `group_coefficients[g]` is the coefficient of every damper in group g.
    pub fn new(structure: &Structure, group_coefficients: &[f64], exponent: f64) -> Result<Self> {
        if !(exponent.is_finite() && exponent > 0.0 && exponent <= 2.0) {
            return Err(Error::invalid("damper_exponent", format!("must lie in (0, 2], got {exponent}")));
        }
        let groups = structure.damper_groups();
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
        let floor_weights = structure
            .dampers
            .iter()
            .map(|d| {
                let mut row = vec![(d.upper_floor, d.cos_angle)];
                if let Some(lower) = d.lower_floor {
                    row.push((lower, -d.cos_angle));
                }
                row
            })
            .collect();
        let coefficients = structure.dampers.iter().map(|d| group_coefficients[d.group]).collect();
        Ok(Dampers { coefficients, exponent, floor_weights })
    }

    pub fn len(&self) -> usize {
        self.coefficients.len()
    }

    pub fn is_empty(&self) -> bool {
        self.coefficients.is_empty()
    }

    /// Axial force of damper d at axial velocity v.
    pub fn force(&self, d: usize, v: f64) -> f64 {
        self.coefficients[d] * v.signum() * v.abs().powf(self.exponent)
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

/// out = x − y.
fn subtract_into(out: &mut [f64], x: &[f64], y: &[f64]) {
    for ((d, x), y) in out.iter_mut().zip(x).zip(y) {
        *d = x - y;
    }
}

/// Newton solver for s = a − W Gᵀ F(G s) with preallocated work space, reused every step.
#[derive(Debug, Clone)]
pub struct ImplicitDamperSolve {
    /// Unknowns per step (modes, or floors).
    size: usize,
    /// W⁻¹, row-major size×size.
    w_inverse: Vec<f64>,
    /// G as sparse rows: damper d's velocity is Σ weight·s[index].
    map: Vec<Vec<(usize, f64)>>,
    coefficients: Vec<f64>,
    exponent: f64,
    hessian: Vec<f64>,
    gradient: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<f64>,
    /// Damper velocities G s at the current iterate and |v|^α of each, kept between the calls
    /// that evaluate the same iterate: a power is the expensive part of an iteration.
    velocities: Vec<f64>,
    powers: Vec<f64>,
    trial_velocities: Vec<f64>,
    trial_powers: Vec<f64>,
    /// Whether `velocities` and `powers` belong to the current iterate.
    current: bool,
    /// Work space for s − a.
    difference: Vec<f64>,
}

impl ImplicitDamperSolve {
    pub fn new(w_inverse: Vec<f64>, map: Vec<Vec<(usize, f64)>>, dampers: &Dampers) -> Self {
        let size = (w_inverse.len() as f64).sqrt().round() as usize;
        ImplicitDamperSolve {
            size,
            w_inverse,
            coefficients: dampers.coefficients.clone(),
            exponent: dampers.exponent,
            map,
            hessian: vec![0.0; size * size],
            gradient: vec![0.0; size],
            step: vec![0.0; size],
            trial: vec![0.0; size],
            velocities: vec![0.0; dampers.len()],
            powers: vec![0.0; dampers.len()],
            trial_velocities: vec![0.0; dampers.len()],
            trial_powers: vec![0.0; dampers.len()],
            current: false,
            difference: vec![0.0; size],
        }
    }

    fn damper_velocities(map: &[Vec<(usize, f64)>], s: &[f64], out: &mut [f64]) {
        for (v, row) in out.iter_mut().zip(map) {
            *v = row.iter().map(|&(i, w)| w * s[i]).sum();
        }
    }

    /// Velocities G s and their powers |v|^α.
    fn evaluate(&self, s: &[f64], velocities: &mut [f64], powers: &mut [f64]) {
        Self::damper_velocities(&self.map, s, velocities);
        for (p, v) in powers.iter_mut().zip(velocities.iter()) {
            *p = v.abs().powf(self.exponent);
        }
    }

    /// J(s), given the damper velocities of s and their powers |v|^α (|v|^{1+α} = |v|·|v|^α);
    /// `difference` is work space.
    fn objective(&self, s: &[f64], a: &[f64], velocities: &[f64], powers: &[f64], difference: &mut [f64]) -> f64 {
        subtract_into(difference, s, a);
        let difference = &*difference;
        let quadratic: f64 =
            self.w_inverse.chunks_exact(self.size).zip(difference).map(|(row, d)| d * dot(row, difference)).sum();
        let p = 1.0 + self.exponent;
        let dissipation: f64 =
            velocities.iter().zip(powers).zip(&self.coefficients).map(|((v, pw), c)| c / p * v.abs() * pw).sum();
        0.5 * quadratic + dissipation
    }

    /// Fills `forces` and the gradient W⁻¹(s − a) + Gᵀ F at `s`, and the Hessian model
    /// W⁻¹ + Gᵀ diag(w_d) G with w_d = c·factor·|v|^{α−1}: factor α gives Newton's tangent, factor 1
    /// the secant curvature of the majorizer.
    fn linearise(&mut self, s: &[f64], a: &[f64], forces: &mut [f64], curvature_factor: f64, floor: f64) {
        let n = self.size;
        let alpha = self.exponent;
        if !self.current {
            let (mut velocities, mut powers) = (std::mem::take(&mut self.velocities), std::mem::take(&mut self.powers));
            self.evaluate(s, &mut velocities, &mut powers);
            (self.velocities, self.powers) = (velocities, powers);
            self.current = true;
        }
        subtract_into(&mut self.difference, s, a);
        for (g, row) in self.gradient.iter_mut().zip(self.w_inverse.chunks_exact(n)) {
            *g = dot(row, &self.difference);
        }
        self.hessian.copy_from_slice(&self.w_inverse);
        for (d, row) in self.map.iter().enumerate() {
            let v = self.velocities[d];
            let c = self.coefficients[d];
            let magnitude = v.abs();
            let f = c * v.signum() * self.powers[d];
            forces[d] = f;
            let slope = if magnitude > floor { self.powers[d] / magnitude } else { floor.powf(alpha - 1.0) };
            let weight = c * curvature_factor * slope;
            for &(i, wi) in row {
                self.gradient[i] += wi * f;
                for &(j, wj) in row {
                    self.hessian[i * n + j] += weight * wi * wj;
                }
            }
        }
    }

    fn take_trial_step(&mut self, s: &[f64]) {
        for ((trial, x), step) in self.trial.iter_mut().zip(s).zip(&self.step) {
            *trial = x + step;
        }
    }

    /// step = −H⁻¹ g with the Hessian model of the last [`Self::linearise`].
    fn model_step(&mut self) -> Result<()> {
        let n = self.size;
        if !cholesky(&mut self.hessian, n) {
            return Err(Error::Numerical("the damper Newton system lost positive definiteness".into()));
        }
        for i in 0..n {
            self.step[i] = -self.gradient[i];
        }
        cholesky_solve(&self.hessian, n, &mut self.step);
        Ok(())
    }

    /// Solves for the new velocities. `s` holds the initial guess on entry and the solution on exit;
    /// `forces` receives the axial damper forces at the solution. Returns the iterations used.
    ///
    /// Each iteration tries Newton's step and keeps it if J falls enough (Armijo). Otherwise it takes
    /// the majorize-minimize step instead: |v|^{1+α} is concave in v², so the quadratic with the
    /// secant curvature c|v|^{α−1} lies above J and touches it at s, and its minimiser lowers J
    /// without a line search. That is what converges where a damper comes to rest at the solution,
    /// where Newton overshoots by the factor 1 − 1/α.
    pub fn solve(&mut self, a: &[f64], s: &mut [f64], forces: &mut [f64]) -> Result<usize> {
        self.current = false;
        for iteration in 0..MAX_NEWTON_ITERATIONS {
            let scale = s.iter().chain(a).fold(0.0f64, |m, x| m.max(x.abs()));
            let tolerance = STEP_TOLERANCE * scale + f64::MIN_POSITIVE;
            let floor = HESSIAN_FLOOR_FRACTION * tolerance;
            self.linearise(s, a, forces, self.exponent, floor);
            self.model_step()?;
            let largest_step = self.step.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if largest_step <= tolerance {
                s.iter_mut().zip(&self.step).for_each(|(x, d)| *x += d);
                let (mut velocities, mut powers) =
                    (std::mem::take(&mut self.velocities), std::mem::take(&mut self.powers));
                self.evaluate(s, &mut velocities, &mut powers);
                for (d, f) in forces.iter_mut().enumerate() {
                    *f = self.coefficients[d] * velocities[d].signum() * powers[d];
                }
                (self.velocities, self.powers) = (velocities, powers);
                return Ok(iteration + 1);
            }
            let mut difference = std::mem::take(&mut self.difference);
            let current = self.objective(s, a, &self.velocities, &self.powers, &mut difference);
            let slope: f64 = self.gradient.iter().zip(&self.step).map(|(g, d)| g * d).sum();
            self.take_trial_step(s);
            let (mut velocities, mut powers) =
                (std::mem::take(&mut self.trial_velocities), std::mem::take(&mut self.trial_powers));
            self.evaluate(&self.trial, &mut velocities, &mut powers);
            let value = self.objective(&self.trial, a, &velocities, &powers, &mut difference);
            (self.trial_velocities, self.trial_powers, self.difference) = (velocities, powers, difference);
            if value <= current + 1e-4 * slope {
                // The trial is the next iterate: its velocities and powers are already known.
                std::mem::swap(&mut self.velocities, &mut self.trial_velocities);
                std::mem::swap(&mut self.powers, &mut self.trial_powers);
            } else {
                self.linearise(s, a, forces, 1.0, floor);
                self.model_step()?;
                self.take_trial_step(s);
                self.current = false;
            }
            s.copy_from_slice(&self.trial);
        }
        Err(Error::Numerical(format!("the damper forces did not converge in {MAX_NEWTON_ITERATIONS} iterations")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn single(c: f64, alpha: f64) -> Dampers {
        Dampers { coefficients: vec![c], exponent: alpha, floor_weights: vec![vec![(0, 1.0)]] }
    }

    /// One unknown, one damper: s + w c sgn(s)|s|^α = a, a monotone scalar equation whose root
    /// bisection finds independently. Starts on the wrong side, at zero, a stiff damper (w c large)
    /// and a root at zero (where |v|^α has its infinite slope) all converge.
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
            for start in [0.0, -5.0, 5.0, a] {
                let mut s = [start];
                let mut f = [0.0];
                solver.solve(&[a], &mut s, &mut f).unwrap();
                assert!(
                    (s[0] - root).abs() < 1e-10 * a.abs() + 1e-14,
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
}
