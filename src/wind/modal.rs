//! The fast path to the modal forces: Q(t) = Φᵀ(η∘v̄²) + A v(t) with A = Φᵀ diag(2η_j v̄_j),
//! simulated directly as an n_modes-variate process whose cross-spectral matrix is A S Aᵀ, on a
//! coarse grid, with one spectral table for every wind speed.
//!
//! Every quantity of the wind model scales with the station speed v̄: the mean speeds v̄_z and v*
//! are proportional to it, the PSD's shape and the coherence depend on ω only through ω/v̄, and A is
//! proportional to v̄. Hence S_Q(ω; v̄) = v̄³ G(ω/v̄) with G the projected spectrum at 1 m/s, which
//! is tabulated once per structure; a sample then costs a table look-up per frequency instead of a
//! 40×40 coherence matrix projected at each of its 3·2048 frequencies.

use super::histories::{CoarseModalForces, ModalForces};
use super::loads::WindLoads;
use super::spectral::{CrossSpectralDensity, SpectralGrid, simulate_coarse};
use super::spectrum::ProjectedSpectrum;
use super::{StormGrid, TransformWorkspace};
use crate::error::Result;
use crate::linalg::cholesky_through_column;
use crate::uncertainty::Rng;
use faer::{Mat, MatRef};

/// Table points per decade of reduced frequency; cubic interpolation in ln u then errs by less
/// than 10⁻⁷ of the diagonal (4·10⁻⁸ measured, tests below), far below the scheme's own
/// discretisation (~1 %) and any sampling error.
const POINTS_PER_DECADE: f64 = 160.0;
/// Station speeds (m/s) the table serves; outside them the spectrum is projected exactly.
const TABLE_SPEEDS: (f64, f64) = (1.0, 150.0);

/// The lower Cholesky factor L(u) of G(u) = S_Q(u; 1 m/s) on a logarithmic grid of reduced
/// frequency u = ω/v̄ (rad/m). Tabulating the factor rather than G spares every sample a
/// factorisation per frequency: the factor of v̄³G is v̄^{3/2}L. L is as smooth in ln u as G (G is
/// positive definite; where the coherence tends to one its last pivots go as √u, smooth in ln u).
#[derive(Debug, Clone)]
struct ModalSpectrumTable {
    dim: usize,
    points: usize,
    log_first: f64,
    log_step: f64,
    /// Entry e = a·dim + b (lower triangle) of L at point k: factors[e·points + k], so that the
    /// four points an interpolation reads are adjacent.
    factors: Vec<f64>,
    /// ln k / log_step for k = 1 … dim·lines: the scheme's frequencies are ω = kΔω/dim, so a
    /// sample finds a line's place in the table by an addition instead of a logarithm.
    line_positions: Vec<f64>,
}

/// Where a frequency falls in the table: its first of four points and their Lagrange weights.
#[derive(Debug, Clone, Copy, Default)]
struct Stencil {
    first: usize,
    weights: [f64; 4],
}

impl ModalSpectrumTable {
    fn new(unit: &ProjectedSpectrum, grid: &SpectralGrid) -> Self {
        let dim = unit.dim();
        // The lowest frequency a sample uses is Δω/n at the fastest wind, the highest ω_up at the slowest.
        let lowest = grid.step() / dim as f64 / TABLE_SPEEDS.1;
        let highest = grid.cutoff / TABLE_SPEEDS.0;
        let log_step = std::f64::consts::LN_10 / POINTS_PER_DECADE;
        let log_first = lowest.ln() - 2.0 * log_step;
        let points = ((highest.ln() - log_first) / log_step).ceil() as usize + 3;
        let mut factors = vec![0.0; points * dim * dim];
        let mut factor = vec![0.0; dim * dim];
        for k in 0..points {
            let u = (log_first + k as f64 * log_step).exp();
            unit.sweep(u, 0.0, 1, &mut |_, s| factor.copy_from_slice(s));
            cholesky_through_column(&mut factor, dim, dim - 1);
            for (e, value) in factor.iter().enumerate() {
                factors[e * points + k] = *value;
            }
        }
        let line_positions = (1..=dim * grid.lines).map(|k| (k as f64).ln() / log_step).collect();
        ModalSpectrumTable { dim, points, log_first, log_step, factors, line_positions }
    }

    /// The stencil of the frequency at `position` = (ln u − log_first)/log_step.
    #[inline]
    fn stencil(&self, position: f64) -> Stencil {
        // Within the table the floor; outside it the end intervals extrapolate.
        let i = position.floor().clamp(1.0, (self.points - 3) as f64);
        let t = position - i;
        let weights = [
            -t * (t - 1.0) * (t - 2.0) / 6.0,
            (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
            -(t + 1.0) * t * (t - 2.0) / 2.0,
            (t + 1.0) * t * (t - 1.0) / 6.0,
        ];
        Stencil { first: i as usize - 1, weights }
    }

    /// The table position of reduced frequency u.
    fn position(&self, u: f64) -> f64 {
        (u.ln() - self.log_first) / self.log_step
    }

    /// Entry e (a·dim + b) of L at a stencil.
    #[inline]
    fn entry(&self, e: usize, stencil: &Stencil) -> f64 {
        let at = &self.factors[e * self.points + stencil.first..][..4];
        let w = &stencil.weights;
        w[0] * at[0] + w[1] * at[1] + w[2] * at[2] + w[3] * at[3]
    }
}

/// The table scaled to one station speed: S_Q(ω) = v̄³ G(ω/v̄), factor v̄^{3/2} L(ω/v̄).
struct ScaledSpectrum<'a> {
    table: &'a ModalSpectrumTable,
    speed: f64,
}

impl ScaledSpectrum<'_> {
    /// The stencils of ω_l = ω₀ + l·Δω, l < count. On the scheme's grid ω_l = (k₀ + l·n)·Δω/n with
    /// k₀ whole and ln u = ln k + ln(Δω/(n v̄)), read from the table of ln k.
    fn stencils(&self, omega0: f64, domega: f64, count: usize) -> Vec<Stencil> {
        let table = self.table;
        let n = table.dim;
        let first = omega0 * n as f64 / domega;
        let k0 = first.round() as usize;
        let on_grid = k0 >= 1
            && (first - k0 as f64).abs() <= 1e-9 * first
            && k0 + (count.max(1) - 1) * n <= table.line_positions.len();
        let shift = table.position(domega / (n as f64 * self.speed));
        let position = |l: usize| -> f64 {
            if on_grid {
                table.line_positions[k0 - 1 + l * n] + shift
            } else {
                table.position((omega0 + l as f64 * domega) / self.speed)
            }
        };
        (0..count).map(|l| table.stencil(position(l))).collect()
    }
}

impl CrossSpectralDensity for ScaledSpectrum<'_> {
    fn dim(&self) -> usize {
        self.table.dim
    }

    /// S = v̄³ L Lᵀ from the interpolated factor.
    fn sweep(&self, omega0: f64, domega: f64, count: usize, visit: &mut dyn FnMut(usize, &[f64])) {
        let n = self.table.dim;
        let cube = self.speed.powi(3);
        let (mut factor, mut s) = (vec![0.0; n * n], vec![0.0; n * n]);
        for (l, stencil) in self.stencils(omega0, domega, count).iter().enumerate() {
            for (e, f) in factor.iter_mut().enumerate() {
                *f = if e % n <= e / n { self.table.entry(e, stencil) } else { 0.0 };
            }
            for a in 0..n {
                for b in 0..=a {
                    s[a * n + b] = cube * (0..=b).map(|k| factor[a * n + k] * factor[b * n + k]).sum::<f64>();
                }
            }
            visit(l, &s);
        }
    }

    fn factor_columns(&self, omega0: f64, domega: f64, m: usize, columns: &mut [f64]) {
        let n = self.table.dim;
        let scale = self.speed.powf(1.5);
        let lines = columns.len() / n;
        let stencils = self.stencils(omega0, domega, lines);
        for (j, column) in columns.chunks_exact_mut(lines).enumerate().skip(m) {
            for (c, stencil) in column.iter_mut().zip(&stencils) {
                *c = scale * self.table.entry(j * n + m, stencil);
            }
        }
    }
}

/// The modal-force generator of one structure at one site.
#[derive(Debug, Clone)]
pub struct ModalWind {
    loads: WindLoads,
    /// Roof-normalised shapes of the retained modes, floors × modes.
    shapes: Mat<f64>,
    table: ModalSpectrumTable,
}

impl ModalWind {
    /// The generator for the modes `shapes` (floors × modes), its modal spectrum tabulated once.
    pub fn new(loads: &WindLoads, shapes: MatRef<'_, f64>) -> Self {
        let unit = loads.spectrum(1.0);
        let table = ModalSpectrumTable::new(&Self::projected(loads, shapes, &unit), &loads.grid());
        ModalWind { loads: loads.clone(), shapes: shapes.to_owned(), table }
    }

    fn projected<'a>(
        loads: &WindLoads,
        shapes: MatRef<'_, f64>,
        field: &'a super::FieldSpectrum,
    ) -> ProjectedSpectrum<'a> {
        let projection = Mat::from_fn(shapes.ncols(), shapes.nrows(), |m, j| {
            shapes[(j, m)] * 2.0 * loads.exposure[j] * field.mean_speeds[j]
        });
        ProjectedSpectrum { field, projection }
    }

    /// One storm of `duration` seconds at station speed `wind_speed`, on the generation grid, with
    /// the transforms of `workspace`.
    pub fn simulate(
        &self,
        wind_speed: f64,
        duration: f64,
        workspace: &mut TransformWorkspace,
        rng: &mut Rng,
    ) -> Result<CoarseModalForces> {
        WindLoads::check_speed(wind_speed)?;
        let shapes = self.shapes.as_ref();
        let mean_forces = self.loads.mean_forces(wind_speed);
        let mean: Vec<f64> =
            (0..shapes.ncols()).map(|m| (0..shapes.nrows()).map(|j| shapes[(j, m)] * mean_forces[j]).sum()).collect();
        let grid = self.loads.grid();
        let step = self.loads.site.field_generation_step_s;
        let fluctuations = if (TABLE_SPEEDS.0..=TABLE_SPEEDS.1).contains(&wind_speed) {
            simulate_coarse(
                &ScaledSpectrum { table: &self.table, speed: wind_speed },
                &grid,
                step,
                duration,
                workspace,
                rng,
            )?
        } else {
            let field = self.loads.spectrum(wind_speed);
            simulate_coarse(&Self::projected(&self.loads, shapes, &field), &grid, step, duration, workspace, rng)?
        };
        Ok(CoarseModalForces { mean, fluctuations })
    }

    /// One storm on `storm`'s grid.
    pub fn forces(&self, wind_speed: f64, storm: &StormGrid, rng: &mut Rng) -> Result<ModalForces> {
        Ok(self.simulate(wind_speed, storm.duration, &mut TransformWorkspace::default(), rng)?.on_grid(storm))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::Study;
    use crate::uncertainty::rng_from_seed;
    use crate::wind::spectral::unit_phases;
    use rustfft::num_complex::Complex;

    /// The single-precision transforms at the paper's full size (3 modes, 2048 lines, a 900 s
    /// storm): the simulated modal forces equal the direct double-precision sum of Eq. (15) over
    /// the same phases and factor at instants spread over the storm, to 10⁻⁵ of each force's
    /// standard deviation (the rounding seen is ~10⁻⁷ of it).
    #[test]
    fn single_precision_storm_equals_the_direct_sum() {
        let p = Study::preset("frame40").unwrap();
        let wind = ModalWind::new(&p.wind, p.modes.shapes.as_ref());
        let (speed, seed) = (31.0, 3);
        let coarse = wind
            .simulate(speed, 900.0, &mut TransformWorkspace::default(), &mut rng_from_seed(seed))
            .unwrap()
            .fluctuations;
        let grid = p.wind.grid();
        let (n, lines, dw) = (3, grid.lines, grid.step());
        let phases = unit_phases(&mut rng_from_seed(seed), n * lines);
        let scaled = ScaledSpectrum { table: &wind.table, speed };
        let columns: Vec<Vec<f64>> = (0..n)
            .map(|m| {
                let mut column = vec![0.0; n * lines];
                scaled.factor_columns((m + 1) as f64 * dw / n as f64, dw, m, &mut column);
                column
            })
            .collect();
        let mut checked = 0;
        for q in (0..coarse.series[0].len()).step_by(997) {
            let t = (q as f64 - 1.0) * coarse.step;
            for j in 0..n {
                let (mut sum, mut variance) = (0.0, 0.0);
                for (m, column) in columns.iter().enumerate().take(j + 1) {
                    for l in 0..lines {
                        let h = column[j * lines + l];
                        let omega = l as f64 * dw + (m + 1) as f64 * dw / n as f64;
                        let phase = phases[m * lines + l];
                        let phase = Complex::new(f64::from(phase.re), f64::from(phase.im));
                        sum += 2.0 * h * dw.sqrt() * (phase * Complex::from_polar(1.0, omega * t)).re;
                        variance += 2.0 * h * h * dw;
                    }
                }
                let error = (coarse.series[j][q] - sum).abs() / variance.sqrt();
                assert!(error < 1e-5, "mode {j}, t = {t} s: {} vs {sum} ({error:e} sd)", coarse.series[j][q]);
                checked += 1;
            }
        }
        assert!(checked >= 27, "{checked} values checked");
    }

    /// The scaling identity and the interpolation together: the tabulated spectrum at several
    /// speeds equals the projection of the full 40-floor spectrum at that speed, at frequencies
    /// between the table's points, to 10⁻⁷ of the diagonal.
    #[test]
    fn table_equals_the_projected_spectrum_at_every_speed() {
        let p = Study::preset("frame40").unwrap();
        let shapes = p.modes.shapes.as_ref();
        let wind = ModalWind::new(&p.wind, shapes);
        let mut worst = 0.0f64;
        for speed in [1.5, 12.0, 30.0, 47.3, 140.0] {
            let field = p.wind.spectrum(speed);
            let exact = ModalWind::projected(&p.wind, shapes, &field);
            let scaled = ScaledSpectrum { table: &wind.table, speed };
            // From the scheme's lowest frequency Δω/n up, off the table's points.
            let (omega0, domega) = (p.wind.site.cutoff_rad_s / p.wind.site.frequencies as f64 / 3.0, 0.0123);
            let mut expected = Vec::new();
            exact.sweep(omega0, domega, 500, &mut |_, s| expected.push(s.to_vec()));
            scaled.sweep(omega0, domega, 500, &mut |l, s| {
                for a in 0..3 {
                    for b in 0..=a {
                        let e = &expected[l];
                        let scale = (e[a * 3 + a] * e[b * 3 + b]).sqrt();
                        worst = worst.max((s[a * 3 + b] - e[a * 3 + b]).abs() / scale);
                    }
                }
            });
        }
        assert!(worst < 1e-7, "largest relative error {worst:e}");
    }

    /// The tabulated factor's columns are the Cholesky factor of the spectrum the table gives, on
    /// an arbitrary arithmetic sequence of frequencies and on the scheme's own (where the
    /// logarithms come from the table of ln k).
    #[test]
    fn factor_columns_factor_the_tabulated_spectrum() {
        struct Plain<'a>(&'a ScaledSpectrum<'a>);
        impl CrossSpectralDensity for Plain<'_> {
            fn dim(&self) -> usize {
                3
            }
            fn sweep(&self, omega0: f64, domega: f64, count: usize, visit: &mut dyn FnMut(usize, &[f64])) {
                self.0.sweep(omega0, domega, count, visit)
            }
        }
        let p = Study::preset("frame40").unwrap();
        let wind = ModalWind::new(&p.wind, p.modes.shapes.as_ref());
        let scaled = ScaledSpectrum { table: &wind.table, speed: 33.0 };
        let scheme = p.wind.grid().step();
        // (ω₀ of column m = first + (m + 1)·shift, Δω, lines)
        let grids = [(0.001, 0.0, 0.0173, 300), (0.0, scheme / 3.0, scheme, p.wind.site.frequencies)];
        for (first, shift, domega, lines) in grids {
            let omega0 = |m: usize| first + (m + 1) as f64 * shift;
            for m in 0..3 {
                let (mut plain, mut table) = (vec![0.0; lines * 3], vec![0.0; lines * 3]);
                Plain(&scaled).factor_columns(omega0(m), domega, m, &mut plain);
                scaled.factor_columns(omega0(m), domega, m, &mut table);
                let diagonal = &table[m * lines..(m + 1) * lines];
                for j in m..3 {
                    let (a, b) = (&plain[j * lines..(j + 1) * lines], &table[j * lines..(j + 1) * lines]);
                    for ((x, y), d) in a.iter().zip(b).zip(diagonal) {
                        assert!((x - y).abs() <= 1e-9 * d.abs(), "column {m}, row {j}: {x} vs {y}");
                    }
                }
            }
        }
    }
}
