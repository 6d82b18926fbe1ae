//! The reduced-order reference for eight storms at once, one storm per lane of [`LANES`]: the same
//! exponential integrator and the same implicit damper solve as [`super::integrate_reduced`], with
//! every operation a pass over the lanes so that it runs in vector registers.
//!
//! One storm at a time, a step is a few dozen scalar operations per damper wrapped in branches and
//! bookkeeping (which damper's weight changed, whether to refactor), and the damper powers run four
//! to a register at best. In lanes each operation serves eight storms, the 3×3 Newton matrix is
//! simply formed and factored afresh every iteration (cheaper than deciding not to, at this size),
//! and the Newton solve's branches become masks: a lane whose iterate has converged is frozen while
//! the others iterate, a lane whose Newton step fails Armijo's test takes the majorize-minimize
//! step while the others keep theirs. The iterates are those of the one-storm solve up to its
//! factor-reuse shortcuts, so the answers agree with it to the solve's tolerance (10⁻⁹ of the
//! velocities), not to the bit.

use super::damper::Dampers;
use super::modal::{ModalResponse, StepCoefficients};
use super::power::power_lanes;
use crate::error::{Error, Result};
use crate::progress::{CHECK_EVERY_STEPS, Observer, check};
use crate::simd::{LANES, Lanes};
use crate::structure::Modes;
use crate::wind::ModalForces;
use std::array::from_fn;

/// As the one-storm solve: at most this many Newton iterations per step.
const MAX_NEWTON_ITERATIONS: usize = 100;
/// As the one-storm solve: converged when no velocity moves by more than this fraction of the
/// largest one.
const STEP_TOLERANCE: f64 = 1e-9;
/// As the one-storm solve: damper velocities below this fraction of the tolerance count as it in
/// the Newton matrix.
const HESSIAN_FLOOR_FRACTION: f64 = 1e-2;

/// One storm of a batch: a sample's reduced model and its modal forces.
#[derive(Clone, Copy)]
pub struct ReducedStorm<'a> {
    /// The sample's modes (frequencies and generalized masses scaled).
    pub modes: &'a Modes,
    /// Its structural damping ratio.
    pub damping_ratio: f64,
    /// Its dampers.
    pub dampers: &'a Dampers,
    /// Its modal forces on the storm's grid.
    pub forces: &'a ModalForces,
}

/// Integrates up to [`LANES`] storms of one structure together (same modes retained, same dampers
/// and exponent, same number of steps), each from its static equilibrium under its mean load; the
/// responses are in the storms' order. Lanes beyond the storms given repeat the first storm and
/// are discarded.
pub fn integrate_reduced_lanes(
    storms: &[ReducedStorm<'_>],
    time_step: f64,
    observer: &dyn Observer,
) -> Result<Vec<ModalResponse>> {
    let batch = Batch::new(storms, time_step)?;
    batch.integrate(storms, observer)
}

/// Lane `l`'s storm: the storm given, or the first where fewer than [`LANES`] were.
#[inline(always)]
fn storm_of<'s, 'a>(storms: &'s [ReducedStorm<'a>], l: usize) -> &'s ReducedStorm<'a> {
    storms.get(l).unwrap_or(&storms[0])
}

/// A batch's fixed data, lane by lane.
struct Batch {
    modes: usize,
    dampers: usize,
    steps: usize,
    exponent: f64,
    /// Per mode: E, Γ₀ − Γ₁ and Γ₁ (rows: displacement, velocity).
    transition: Vec<[[Lanes; 2]; 2]>,
    gamma_difference: Vec<[Lanes; 2]>,
    gamma1: Vec<[Lanes; 2]>,
    /// Per mode: 1/M_m and W⁻¹'s diagonal M_m/Γ₁[1].
    inverse_masses: Vec<Lanes>,
    w_inverse: Vec<Lanes>,
    /// Per damper: its coefficient.
    coefficients: Vec<Lanes>,
    /// G_dm (damper velocity Σ_m G_dm ẏ_m) damper by damper, `[d·modes + m]`, and mode by mode,
    /// `[m·dampers + d]`: each sum then runs along contiguous memory into one register.
    map: Vec<Lanes>,
    map_by_mode: Vec<Lanes>,
    /// Per mode: the static displacement under the mean load.
    rest: Vec<Lanes>,
}

impl Batch {
    fn new(storms: &[ReducedStorm<'_>], time_step: f64) -> Result<Self> {
        let first = storms.first().ok_or_else(|| Error::invalid("storms", "a batch needs at least one storm"))?;
        if storms.len() > LANES {
            return Err(Error::invalid("storms", format!("at most {LANES} per batch, got {}", storms.len())));
        }
        let modes = first.modes.count();
        let dampers = first.dampers.len();
        let steps = first.forces.series.first().map_or(0, Vec::len);
        for (k, storm) in storms.iter().enumerate() {
            let shape_ok = storm.modes.count() == modes
                && storm.dampers.len() == dampers
                && storm.dampers.exponent == first.dampers.exponent
                && storm.forces.series.len() == modes
                && storm.forces.series.iter().all(|series| series.len() == steps);
            if !shape_ok {
                return Err(Error::invalid(
                    "storms",
                    format!("storm {k} differs from the first in modes, dampers, exponent or steps"),
                ));
            }
        }
        if steps == 0 {
            return Err(Error::invalid("forces", "a storm needs at least one step"));
        }
        let coefficients: Vec<[StepCoefficients; LANES]> = (0..modes)
            .map(|m| {
                from_fn(|l| {
                    let s = storm_of(storms, l);
                    StepCoefficients::new(s.modes.frequencies[m], s.damping_ratio, time_step)
                })
            })
            .collect();
        let per_mode = |f: &dyn Fn(&ReducedStorm<'_>, &StepCoefficients, usize) -> f64| -> Vec<Lanes> {
            (0..modes).map(|m| from_fn(|l| f(storm_of(storms, l), &coefficients[m][l], m))).collect()
        };
        let maps: Vec<Vec<Vec<(usize, f64)>>> = (0..LANES)
            .map(|l| storm_of(storms, l).dampers.modal_map(storm_of(storms, l).modes.shapes.as_ref()))
            .collect();
        Ok(Batch {
            modes,
            dampers,
            steps,
            exponent: first.dampers.exponent,
            transition: coefficients.iter().map(|c| from_fn(|r| from_fn(|k| from_fn(|l| c[l].e[r][k])))).collect(),
            gamma_difference: coefficients
                .iter()
                .map(|c| from_fn(|r| from_fn(|l| c[l].gamma0[r] - c[l].gamma1[r])))
                .collect(),
            gamma1: coefficients.iter().map(|c| from_fn(|r| from_fn(|l| c[l].gamma1[r]))).collect(),
            inverse_masses: per_mode(&|s, _, m| 1.0 / s.modes.modal_masses[m]),
            w_inverse: per_mode(&|s, c, m| s.modes.modal_masses[m] / c.gamma1[1]),
            coefficients: (0..dampers).map(|d| from_fn(|l| storm_of(storms, l).dampers.coefficients[d])).collect(),
            map: (0..dampers * modes).map(|k| from_fn(|l| modal_weight(&maps[l][k / modes], k % modes))).collect(),
            map_by_mode: (0..modes * dampers)
                .map(|k| from_fn(|l| modal_weight(&maps[l][k % dampers], k / dampers)))
                .collect(),
            rest: per_mode(&|s, _, m| {
                s.forces.mean[m] / (s.modes.modal_masses[m] * s.modes.frequencies[m] * s.modes.frequencies[m])
            }),
        })
    }

    fn integrate(&self, storms: &[ReducedStorm<'_>], observer: &dyn Observer) -> Result<Vec<ModalResponse>> {
        let (n, steps) = (self.modes, self.steps);
        let mut y = self.rest.clone();
        let mut v = vec![[0.0; LANES]; n];
        let mut load: Vec<Lanes> =
            (0..n).map(|m| from_fn(|l| storm_of(storms, l).forces.series[m][0] * self.inverse_masses[m][l])).collect();
        let mut responses: Vec<ModalResponse> = (0..storms.len())
            .map(|l| {
                let series = |first: &dyn Fn(usize) -> f64| -> Vec<Vec<f64>> {
                    (0..n)
                        .map(|m| {
                            let mut series = Vec::with_capacity(steps);
                            series.push(first(m));
                            series
                        })
                        .collect()
                };
                ModalResponse { displacements: series(&|m| y[m][l]), velocities: series(&|_| 0.0) }
            })
            .collect();
        let active = self.coefficients.iter().flatten().any(|&c| c > 0.0);
        let mut solve = LaneSolve::new(self);
        let mut known = vec![[[0.0; LANES]; 2]; n];
        // Per mode, this step's modal force over the mass.
        let mut next = vec![[0.0; LANES]; n];
        // Per mode, the modal damper force over the mass, g_m/M_m, of the last step.
        let mut damper_load = vec![[0.0; LANES]; n];
        let mut previous_load = vec![[0.0; LANES]; n];
        for i in 1..steps {
            if i % CHECK_EVERY_STEPS == 0 {
                check(observer)?;
            }
            for m in 0..n {
                next[m] = from_fn(|l| storm_of(storms, l).forces.series[m][i] * self.inverse_masses[m][l]);
                let (e, gd, g1, q) = (&self.transition[m], &self.gamma_difference[m], &self.gamma1[m], &next[m]);
                known[m] = from_fn(|r| {
                    from_fn(|l| e[r][0][l] * y[m][l] + e[r][1][l] * v[m][l] + gd[r][l] * load[m][l] + g1[r][l] * q[l])
                });
                solve.a[m] = known[m][1];
                // Predictor: the damper forces extrapolated linearly from the last two steps.
                let (now, before) = (&damper_load[m], &previous_load[m]);
                solve.s[m] = from_fn(|l| known[m][1][l] - g1[1][l] * (2.0 * now[l] - before[l]));
            }
            if active {
                solve.solve(self, i)?;
                for m in 0..n {
                    previous_load[m] = damper_load[m];
                    damper_load[m] = from_fn(|l| solve.modal_forces[m][l] * self.inverse_masses[m][l]);
                }
            }
            for m in 0..n {
                let g1 = &self.gamma1[m];
                y[m] = from_fn(|l| known[m][0][l] - g1[0][l] * damper_load[m][l]);
                v[m] = from_fn(|l| known[m][1][l] - g1[1][l] * damper_load[m][l]);
                load[m] = from_fn(|l| next[m][l] - damper_load[m][l]);
            }
            for (l, response) in responses.iter_mut().enumerate() {
                for m in 0..n {
                    if !y[m][l].is_finite() {
                        return Err(Error::Numerical(format!(
                            "the reduced model of storm {l} of the batch diverged at step {i}"
                        )));
                    }
                    response.displacements[m].push(y[m][l]);
                    response.velocities[m].push(v[m][l]);
                }
            }
        }
        Ok(responses)
    }
}

/// Σ_k a_k b_k in every lane.
#[inline(always)]
fn dot_lanes(a: &[Lanes], b: &[Lanes]) -> Lanes {
    let mut sum = [0.0; LANES];
    for (x, y) in a.iter().zip(b) {
        sum = from_fn(|l| x[l].mul_add(y[l], sum[l]));
    }
    sum
}

/// G_dm of mode `m` in a damper's (mode, weight) row.
fn modal_weight(row: &[(usize, f64)], m: usize) -> f64 {
    row.iter().filter(|&&(mode, _)| mode == m).map(|&(_, w)| w).sum()
}

/// The Newton solve of s = a − W Gᵀ F(G s) in every lane at once (see [`super::damper`] for the
/// problem and the iteration), W diagonal here: the exponential integrator's W⁻¹ is
/// diag(M_m/Γ₁[1]).
struct LaneSolve {
    /// The step's a and the iterate s, per mode.
    a: Vec<Lanes>,
    s: Vec<Lanes>,
    /// Per mode, Σ_d G_dm F_d at the solution.
    modal_forces: Vec<Lanes>,
    /// Per damper, the axial force F_d.
    forces: Vec<Lanes>,
    gradient: Vec<Lanes>,
    step: Vec<Lanes>,
    trial: Vec<Lanes>,
    /// The Newton matrix, row-major n×n, factored in place (upper Cholesky factor).
    matrix: Vec<Lanes>,
    /// Per damper: velocity G s and |v|^α at the iterate and at the trial.
    velocities: Vec<Lanes>,
    powers: Vec<Lanes>,
    trial_velocities: Vec<Lanes>,
    trial_powers: Vec<Lanes>,
    weights: Vec<Lanes>,
    /// w_d G_di, `[i·dampers + d]`.
    weighted: Vec<Lanes>,
}

/// `to` in the lanes whose flag is set, `from` elsewhere.
#[inline(always)]
fn select(flags: &[bool; LANES], to: Lanes, from: Lanes) -> Lanes {
    from_fn(|l| if flags[l] { to[l] } else { from[l] })
}

impl LaneSolve {
    fn new(batch: &Batch) -> Self {
        let (n, d) = (batch.modes, batch.dampers);
        let zeros = |k: usize| vec![[0.0; LANES]; k];
        LaneSolve {
            a: zeros(n),
            s: zeros(n),
            modal_forces: zeros(n),
            forces: zeros(d),
            gradient: zeros(n),
            step: zeros(n),
            trial: zeros(n),
            matrix: zeros(n * n),
            velocities: zeros(d),
            powers: zeros(d),
            trial_velocities: zeros(d),
            trial_powers: zeros(d),
            weights: zeros(d),
            weighted: zeros(n * d),
        }
    }

    /// Velocities G s and their powers |v|^α.
    fn evaluate(batch: &Batch, s: &[Lanes], velocities: &mut [Lanes], powers: &mut [Lanes]) {
        let rows = batch.map.chunks_exact(batch.modes);
        for ((v, p), row) in velocities.iter_mut().zip(powers.iter_mut()).zip(rows) {
            *v = dot_lanes(row, s);
            *p = power_lanes(v.map(f64::abs), batch.exponent);
        }
    }

    /// Σ_d c_d/(1+α)·|v_d|^{1+α}.
    fn dissipation(batch: &Batch, velocities: &[Lanes], powers: &[Lanes]) -> Lanes {
        let mut total = [0.0; LANES];
        for ((c, v), p) in batch.coefficients.iter().zip(velocities).zip(powers) {
            total = from_fn(|l| (c[l] * v[l].abs()).mul_add(p[l], total[l]));
        }
        total.map(|t| t / (1.0 + batch.exponent))
    }

    /// The axial forces at the iterate, c·sgn(v)|v|^α, in the lanes still iterating (a converged
    /// lane keeps those it finished with).
    fn forces_at_iterate(&mut self, batch: &Batch, converged: &[bool; LANES]) {
        for (d, force) in self.forces.iter_mut().enumerate() {
            let (c, v, p) = (&batch.coefficients[d], &self.velocities[d], &self.powers[d]);
            *force = from_fn(|l| if converged[l] { force[l] } else { (c[l] * p[l]).copysign(v[l]) });
        }
    }

    /// The axial forces' modal sums Gᵀ F.
    fn modal_sum_of_forces(&mut self, batch: &Batch) {
        for (total, column) in self.modal_forces.iter_mut().zip(batch.map_by_mode.chunks_exact(batch.dampers)) {
            *total = dot_lanes(column, &self.forces);
        }
    }

    /// step = −H⁻¹ gradient with H = W⁻¹ + Σ_d w_d G_d G_dᵀ, w_d = c_d·factor·|v_d|^{α−1}
    /// (velocities below `floor` counting as the floor).
    fn model_step(&mut self, batch: &Batch, factor: f64, floor: &Lanes, floor_slope: &Lanes) -> Result<()> {
        let n = batch.modes;
        for ((w, c), (v, p)) in
            self.weights.iter_mut().zip(&batch.coefficients).zip(self.velocities.iter().zip(&self.powers))
        {
            // Branch-free, so that it vectorises: the quotient is formed in every lane, then chosen.
            let secant: Lanes = from_fn(|l| p[l] / v[l].abs().max(floor[l]));
            *w = from_fn(|l| c[l] * factor * if v[l].abs() > floor[l] { secant[l] } else { floor_slope[l] });
        }
        // H_ij = δ_ij W⁻¹_i + Σ_d (w_d G_di) G_dj, each entry summed in a register.
        let dampers = batch.dampers;
        for (i, weighted) in self.weighted.chunks_exact_mut(dampers).enumerate() {
            for ((x, w), g) in weighted.iter_mut().zip(&self.weights).zip(&batch.map_by_mode[i * dampers..]) {
                *x = from_fn(|l| w[l] * g[l]);
            }
        }
        for i in 0..n {
            let weighted = &self.weighted[i * dampers..(i + 1) * dampers];
            for j in i..n {
                let sum = dot_lanes(weighted, &batch.map_by_mode[j * dampers..(j + 1) * dampers]);
                let diagonal = if i == j { batch.w_inverse[i] } else { [0.0; LANES] };
                self.matrix[i * n + j] = from_fn(|l| sum[l] + diagonal[l]);
            }
        }
        // Upper Cholesky factor H = UᵀU in place, then Uᵀz = −g, U step = z.
        for i in 0..n {
            for k in 0..i {
                let u = self.matrix[k * n + i];
                for j in i..n {
                    let (ukj, entry) = (self.matrix[k * n + j], &mut self.matrix[i * n + j]);
                    *entry = from_fn(|l| (-u[l]).mul_add(ukj[l], entry[l]));
                }
            }
            let pivot = self.matrix[i * n + i];
            if pivot.iter().any(|x| x.is_nan() || *x <= 0.0) {
                return Err(Error::Numerical("the damper Newton system lost positive definiteness".into()));
            }
            let root = pivot.map(f64::sqrt);
            for j in i..n {
                let entry = &mut self.matrix[i * n + j];
                *entry = from_fn(|l| entry[l] / root[l]);
            }
        }
        for i in 0..n {
            let mut z = self.gradient[i].map(|g| -g);
            for k in 0..i {
                let (u, zk) = (self.matrix[k * n + i], self.step[k]);
                z = from_fn(|l| (-u[l]).mul_add(zk[l], z[l]));
            }
            self.step[i] = from_fn(|l| z[l] / self.matrix[i * n + i][l]);
        }
        for i in (0..n).rev() {
            let mut z = self.step[i];
            for k in i + 1..n {
                let (u, xk) = (self.matrix[i * n + k], self.step[k]);
                z = from_fn(|l| (-u[l]).mul_add(xk[l], z[l]));
            }
            self.step[i] = from_fn(|l| z[l] / self.matrix[i * n + i][l]);
        }
        Ok(())
    }

    /// Solves every lane's s = a − W Gᵀ F(G s) from the predictor in `s`; on return `s` holds the
    /// solutions and `modal_forces` Gᵀ F at them. `step_index` names the step in an error.
    fn solve(&mut self, batch: &Batch, step_index: usize) -> Result<()> {
        let n = batch.modes;
        let alpha = batch.exponent;
        Self::evaluate(batch, &self.s, &mut self.velocities, &mut self.powers);
        let mut converged = [false; LANES];
        for _ in 0..MAX_NEWTON_ITERATIONS {
            let mut scale = [0.0f64; LANES];
            for (s, a) in self.s.iter().zip(&self.a) {
                scale = from_fn(|l| scale[l].max(s[l].abs()).max(a[l].abs()));
            }
            let tolerance: Lanes = from_fn(|l| STEP_TOLERANCE * scale[l] + f64::MIN_POSITIVE);
            let floor: Lanes = tolerance.map(|t| HESSIAN_FLOOR_FRACTION * t);
            let floor_slope = power_lanes(floor, alpha - 1.0);
            self.forces_at_iterate(batch, &converged);
            self.modal_sum_of_forces(batch);
            for m in 0..n {
                let (s, a, w) = (&self.s[m], &self.a[m], &batch.w_inverse[m]);
                let f = &self.modal_forces[m];
                self.gradient[m] = from_fn(|l| w[l].mul_add(s[l] - a[l], f[l]));
            }
            self.model_step(batch, alpha, &floor, &floor_slope)?;
            let mut largest = [0.0f64; LANES];
            for step in &self.step {
                largest = from_fn(|l| largest[l].max(step[l].abs()));
            }
            // A lane that converges now takes its last step and is then left alone.
            let finishing: [bool; LANES] = from_fn(|l| !converged[l] && largest[l] <= tolerance[l]);
            let moving: [bool; LANES] = from_fn(|l| !converged[l] && !finishing[l]);
            for (s, step) in self.s.iter_mut().zip(&self.step) {
                *s = select(&finishing, from_fn(|l| s[l] + step[l]), *s);
            }
            // The finishing lanes' forces at s + step by the tangent, F_d + w_d·G_d·step, rather
            // than by new powers: the step is below the tolerance, and so is the difference.
            for d in 0..batch.dampers {
                let moved = dot_lanes(&batch.map[d * n..(d + 1) * n], &self.step);
                let (force, w) = (&mut self.forces[d], &self.weights[d]);
                *force = select(&finishing, from_fn(|l| w[l].mul_add(moved[l], force[l])), *force);
            }
            converged = from_fn(|l| converged[l] || finishing[l]);
            if converged.iter().all(|&c| c) {
                self.modal_sum_of_forces(batch);
                return Ok(());
            }
            // Armijo's test on J's change along the Newton step, computed directly (see the
            // one-storm solve).
            for ((trial, s), step) in self.trial.iter_mut().zip(&self.s).zip(&self.step) {
                *trial = from_fn(|l| s[l] + step[l]);
            }
            Self::evaluate(batch, &self.trial, &mut self.trial_velocities, &mut self.trial_powers);
            let before = Self::dissipation(batch, &self.velocities, &self.powers);
            let after = Self::dissipation(batch, &self.trial_velocities, &self.trial_powers);
            let mut change: Lanes = from_fn(|l| after[l] - before[l]);
            let mut slope = [0.0; LANES];
            for m in 0..n {
                let (p, s, a, w, g) = (&self.step[m], &self.s[m], &self.a[m], &batch.w_inverse[m], &self.gradient[m]);
                change = from_fn(|l| (p[l] * w[l]).mul_add((s[l] - a[l]) + 0.5 * p[l], change[l]));
                slope = from_fn(|l| g[l].mul_add(p[l], slope[l]));
            }
            let accepted: [bool; LANES] = from_fn(|l| moving[l] && change[l] <= 1e-4 * slope[l]);
            for (s, trial) in self.s.iter_mut().zip(&self.trial) {
                *s = select(&accepted, *trial, *s);
            }
            for d in 0..batch.dampers {
                self.velocities[d] = select(&accepted, self.trial_velocities[d], self.velocities[d]);
                self.powers[d] = select(&accepted, self.trial_powers[d], self.powers[d]);
            }
            let rejected: [bool; LANES] = from_fn(|l| moving[l] && !accepted[l]);
            if rejected.iter().any(|&r| r) {
                // The majorize-minimize step: the secant curvature c|v|^{α−1}, no line search.
                self.model_step(batch, 1.0, &floor, &floor_slope)?;
                for (s, step) in self.s.iter_mut().zip(&self.step) {
                    *s = select(&rejected, from_fn(|l| s[l] + step[l]), *s);
                }
                Self::evaluate(batch, &self.s, &mut self.velocities, &mut self.powers);
            }
        }
        Err(Error::Numerical(format!(
            "the damper forces did not converge in {MAX_NEWTON_ITERATIONS} iterations at step {step_index}"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::integrate_reduced;
    use crate::progress::Silent;
    use crate::study::{PhysicalParameters, Study, WindPath};
    use crate::uncertainty::{latin_hypercube, rng_from_seed};

    /// Five storms of `study` at a Latin hypercube's inputs (drawn with `seed`), storm k's wind
    /// from stream k: each sample's parameters and modal forces.
    fn design_storms(study: &Study, seed: u64) -> Vec<(PhysicalParameters, ModalForces)> {
        latin_hypercube(&study.inputs, 5, &mut rng_from_seed(seed))
            .iter()
            .enumerate()
            .map(|(k, x)| {
                let p = study.parameters(x).unwrap();
                let forces = study.modal_forces(&p, WindPath::Modal, &mut rng_from_seed(k as u64)).unwrap();
                (p, forces)
            })
            .collect()
    }

    /// Five storms of frame40-kn at inputs spread over their ranges (a batch with padded lanes),
    /// 120 s each, in lanes and one at a time: every modal displacement and velocity agrees to a
    /// few times the solves' tolerance of 10⁻⁹ of the velocities (each step's solution differs by
    /// at most that, and the dissipative dynamics do not let the differences grow). Failing this
    /// means a lane computed another lane's storm, or a mask let a converged lane move.
    #[test]
    fn lanes_give_the_one_storm_answers() {
        let study = Study::preset("frame40-kn").unwrap().with_storm(120.0, 0.01).unwrap();
        let samples = design_storms(&study, 3);
        let lanes = study.integrate_reduced_batch(&samples, &Silent).unwrap();
        assert_eq!(lanes.len(), 5);
        for ((p, forces), lane) in samples.iter().zip(&lanes) {
            let (modes, dampers) = (study.sample_modes(p), study.dampers(p).unwrap());
            let alone = integrate_reduced(&modes, p.damping_ratio, &dampers, forces, 0.01, &Silent).unwrap();
            for (ours, theirs) in [(&lane.displacements, &alone.displacements), (&lane.velocities, &alone.velocities)] {
                for (a, b) in ours.iter().zip(theirs) {
                    let size = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                    let worst = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                    assert_eq!(a.len(), b.len());
                    assert!(worst <= 1e-8 * size, "worst difference {worst:e} of {size:e}");
                }
            }
        }
    }

    /// A storm's answer does not depend on the batch it is in (what lets a service task of some
    /// experiments give the one-process calibration's numbers to the bit): the third storm of a
    /// batch of five and the same storm alone in a batch (its other lanes repeating it) agree bit
    /// for bit.
    #[test]
    fn a_storm_does_not_depend_on_its_batch() {
        let study = Study::preset("frame40-kn").unwrap().with_storm(60.0, 0.01).unwrap();
        let samples = design_storms(&study, 4);
        let together = study.integrate_reduced_batch(&samples, &Silent).unwrap();
        let alone = study.integrate_reduced_batch(&samples[2..3], &Silent).unwrap();
        let bits = |series: &[Vec<f64>]| -> Vec<Vec<u64>> {
            series.iter().map(|s| s.iter().map(|x| x.to_bits()).collect()).collect()
        };
        assert_eq!(bits(&together[2].displacements), bits(&alone[0].displacements));
        assert_eq!(bits(&together[2].velocities), bits(&alone[0].velocities));
    }

    /// A batch refuses storms of different shapes, and an empty one, naming the field.
    #[test]
    fn a_batch_of_mismatched_storms_is_refused() {
        assert!(integrate_reduced_lanes(&[], 0.01, &Silent).unwrap_err().to_string().contains("storms"));
        let study = Study::preset("frame40-kn").unwrap().with_storm(10.0, 0.01).unwrap();
        let p = study.parameters(&study.inputs.means()).unwrap();
        let forces = study.modal_forces(&p, WindPath::Modal, &mut rng_from_seed(1)).unwrap();
        let mut shorter = forces.clone();
        shorter.series.iter_mut().for_each(|series| series.truncate(100));
        let (modes, dampers) = (study.sample_modes(&p), study.dampers(&p).unwrap());
        let storm = |forces| ReducedStorm { modes: &modes, damping_ratio: p.damping_ratio, dampers: &dampers, forces };
        let error = integrate_reduced_lanes(&[storm(&forces), storm(&shorter)], 0.01, &Silent).unwrap_err();
        assert!(error.to_string().contains("storm 1 differs from the first"), "{error}");
    }
}
