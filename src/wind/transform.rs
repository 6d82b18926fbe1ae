//! The inverse DFT behind the spectral representation, pruned to what a storm reads and run in
//! single precision.
//!
//! A component's term m is Re(e^{iω₀t} h(t)) with h the inverse DFT of length M of a spectrum that
//! is zero beyond its first `lines` bins. Output p = Rq + r is Σ_l b_l e^{2πilr/M} e^{2πilq/L}, the
//! L-point transform of the twisted spectrum (R the largest divisor of M with L = M/R ≥ lines): on
//! the paper's grid (M = 20 480, 2048 lines) ten 2048-point transforms that stay in the cache
//! replace one of 20 480 whose input is nine-tenths zeros. The spectrum is a phase per line (shared
//! by every component j ≥ m) times a real amplitude, so each row's twisted phases are formed once
//! per m and each component only scales them.
//!
//! Single precision: the transforms' rounding, ~10⁻⁷ of the process's standard deviation (bounded
//! in the tests), is five orders below the scheme's own discretisation and any sampling error, and
//! halves the work and memory traffic of the transforms (in double precision they took nearly a
//! quarter of a metamodel sample's processor time). The modulated rows are summed in double
//! precision.

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use std::f64::consts::PI;
use std::sync::Arc;

/// One spectral line or transformed point.
pub(super) type Bin = Complex<f32>;

/// Shapes a [`TransformWorkspace`] keeps; the oldest is dropped past this, so that studies of many
/// different discretisations, one after another, do not accumulate buffers.
const KEPT_SHAPES: usize = 4;

/// The transforms (plans, twiddle factors, buffers) and sums of the shapes a caller has used,
/// built once and reused from storm to storm (a storm's buffers are megabytes, and allocating them
/// afresh cost page faults). A caller that draws many storms keeps one per worker thread, e.g.
/// through rayon's `map_init`.
#[derive(Default)]
pub struct TransformWorkspace {
    /// The kept shapes, oldest first.
    kept: Vec<(PrunedInverse, PolyphaseSum)>,
}

impl TransformWorkspace {
    /// Runs `f` with the transform of the shape (M, lines) and a sum of `components` series of
    /// `count` points, zeroed, that its rows add to.
    pub(super) fn with<T>(
        &mut self,
        len: usize,
        lines: usize,
        components: usize,
        count: usize,
        f: impl FnOnce(&mut PrunedInverse, &mut PolyphaseSum) -> T,
    ) -> T {
        let index = match self.kept.iter().position(|(t, _)| t.len == len && t.lines == lines) {
            Some(index) => index,
            None => {
                let transform = PrunedInverse::new(len, lines);
                let sum = PolyphaseSum::new(transform.rows);
                if self.kept.len() == KEPT_SHAPES {
                    self.kept.remove(0);
                }
                self.kept.push((transform, sum));
                self.kept.len() - 1
            }
        };
        let (transform, sum) = &mut self.kept[index];
        sum.reset(components, count);
        f(transform, sum)
    }
}

/// The pruned inverse transform of one shape (M, lines), with its buffers.
pub(super) struct PrunedInverse {
    len: usize,
    lines: usize,
    rows: usize,
    row_len: usize,
    fft: Arc<dyn Fft<f32>>,
    /// twists[r·lines + l] = e^{2πi·lr/M}, each from its own exact angle.
    twists: Vec<Bin>,
    /// The current m's phases times the twists, laid out as the twists.
    twisted: Vec<Bin>,
    scratch: Vec<Bin>,
    /// The rows being transformed, row r at r·L.
    buffer: Vec<Bin>,
}

impl PrunedInverse {
    fn new(len: usize, lines: usize) -> Self {
        assert!(lines <= len, "more lines than points");
        let rows = (1..=len / lines).rev().find(|r| len.is_multiple_of(*r)).unwrap_or(1);
        let row_len = len / rows;
        let fft = FftPlanner::new().plan_fft_inverse(row_len);
        let twists = (0..rows)
            .flat_map(|r| (0..lines).map(move |l| (l * r) % len))
            .map(|k| {
                let z = Complex::from_polar(1.0, 2.0 * PI * k as f64 / len as f64);
                Bin::new(z.re as f32, z.im as f32)
            })
            .collect();
        let zero = Bin::new(0.0, 0.0);
        PrunedInverse {
            len,
            lines,
            rows,
            row_len,
            scratch: vec![zero; fft.get_inplace_scratch_len()],
            fft,
            twists,
            twisted: vec![zero; rows * lines],
            buffer: vec![zero; len],
        }
    }

    /// Sets the phases of the spectra that follow: line l's is `phases[l]`.
    pub fn set_phases(&mut self, phases: &[Bin]) {
        for (twisted, twists) in self.twisted.chunks_exact_mut(self.lines).zip(self.twists.chunks_exact(self.lines)) {
            for ((out, t), phase) in twisted.iter_mut().zip(twists).zip(phases) {
                *out = phase * t;
            }
        }
    }

    /// The transform of the spectrum amplitudes[l]·phases[l], R rows of L points: row r holds
    /// outputs p = Rq + r, q < L.
    pub fn transform(&mut self, amplitudes: &[f32]) -> &[Bin] {
        for (row, twisted) in self.buffer.chunks_exact_mut(self.row_len).zip(self.twisted.chunks_exact(self.lines)) {
            for ((out, t), a) in row.iter_mut().zip(twisted).zip(amplitudes) {
                *out = t * a;
            }
            row[self.lines..].fill(Bin::new(0.0, 0.0));
        }
        self.fft.process_with_scratch(&mut self.buffer, &mut self.scratch);
        &self.buffer
    }
}

/// Components on a grid of instants p = q − 1 (coarse point q), accumulated by residue of q
/// modulo R: `values[(j·R + r)·C + c]` is point q = Rc + r of component j. A transform's row then
/// adds to one contiguous run, and the sum is put in time order once per component at the end.
pub(super) struct PolyphaseSum {
    count: usize,
    rows: usize,
    per_row: usize,
    values: Vec<f64>,
    /// The current modulation e^{iω₀(q − 1)Δt}, laid out as one component's values.
    modulation: Vec<Bin>,
    /// e^{iω₀RcΔt}, c < C: how far every row of the modulation turns by its point c.
    advance: Vec<Complex<f64>>,
}

impl PolyphaseSum {
    /// An empty sum for a transform of `rows` rows.
    fn new(rows: usize) -> Self {
        PolyphaseSum { count: 0, rows, per_row: 0, values: Vec::new(), modulation: Vec::new(), advance: Vec::new() }
    }

    /// Zero sums of `components` series of `count` points, in the buffers already held.
    fn reset(&mut self, components: usize, count: usize) {
        self.count = count;
        self.per_row = count.div_ceil(self.rows);
        let block = self.rows * self.per_row;
        self.values.clear();
        self.values.resize(components * block, 0.0);
        self.modulation.resize(block, Bin::new(0.0, 0.0));
    }

    /// Sets the modulation of the terms that follow to e^{iω(q − 1)Δt}, given `angle` = ωΔt. Row r
    /// is its first value times the advance e^{iωRcΔt} common to every row, which is formed once
    /// by rotation, anchored exactly every 64 points (the drift stays at rounding level); the rows
    /// are then independent products instead of one long chain of rotations.
    pub fn set_modulation(&mut self, angle: f64) {
        let stride = angle * self.rows as f64;
        let rotation = Complex::from_polar(1.0, stride);
        let mut z = Complex::new(1.0, 0.0);
        self.advance.clear();
        self.advance.extend((0..self.per_row).map(|c| {
            z = if c % 64 == 0 { Complex::from_polar(1.0, stride * c as f64) } else { z * rotation };
            z
        }));
        for (r, row) in self.modulation.chunks_exact_mut(self.per_row).enumerate() {
            let first = Complex::from_polar(1.0, angle * (r as f64 - 1.0));
            for (out, advance) in row.iter_mut().zip(&self.advance) {
                let z = first * advance;
                *out = Bin::new(z.re as f32, z.im as f32);
            }
        }
    }

    /// Adds Re(e^{iω(q − 1)Δt} h(q − 1)) to component j, where `transformed` holds h as R rows
    /// (row r at instants Rc + r) and h has period R·L.
    pub fn add(&mut self, j: usize, transformed: &[Bin]) {
        let row_len = transformed.len() / self.rows;
        let row = |r: usize| &transformed[r * row_len..(r + 1) * row_len];
        let block = self.rows * self.per_row;
        let values = &mut self.values[j * block..(j + 1) * block];
        for (r, (sums, modulation)) in
            values.chunks_exact_mut(self.per_row).zip(self.modulation.chunks_exact(self.per_row)).enumerate()
        {
            // Point q = Rc + r is instant Rc + r − 1: row r − 1 at column c, or for r = 0 the last
            // row one column back.
            let (source, mut column) = if r == 0 { (row(self.rows - 1), row_len - 1) } else { (row(r - 1), 0) };
            let mut done = 0;
            while done < self.per_row {
                let run = (source.len() - column).min(self.per_row - done);
                let points = sums[done..done + run].iter_mut().zip(&source[column..column + run]);
                for ((sum, h), z) in points.zip(&modulation[done..done + run]) {
                    *sum += f64::from(h.re * z.re - h.im * z.im);
                }
                done += run;
                column = 0;
            }
        }
    }

    /// Every component's points in time order.
    pub fn series(&self) -> Vec<Vec<f64>> {
        let block = self.rows * self.per_row;
        self.values
            .chunks_exact(block)
            .map(|values| {
                let mut series = vec![0.0; self.count];
                for (c, points) in series.chunks_mut(self.rows).enumerate() {
                    for (r, point) in points.iter_mut().enumerate() {
                        *point = values[r * self.per_row + c];
                    }
                }
                series
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows and the polyphase sum together equal the direct modulated sum of Eq. (15) for one term,
    /// on a shape with several rows, a column wrap (more points than one period) and a partial last
    /// row, to single-precision rounding of the terms' magnitude.
    #[test]
    fn modulated_rows_equal_the_direct_sum() {
        let (len, lines, count) = (60, 12, 75);
        let phases: Vec<Bin> = (0..lines).map(|l| Bin::from_polar(1.0, 0.7 * l as f32 + 0.3)).collect();
        let amplitudes: Vec<f32> = (0..lines).map(|l| 1.0 / (1.0 + l as f32)).collect();
        let angle = 0.013;
        let series = TransformWorkspace::default().with(len, lines, 1, count, |transform, sum| {
            assert_eq!(transform.rows, 5);
            transform.set_phases(&phases);
            sum.set_modulation(angle);
            sum.add(0, transform.transform(&amplitudes));
            sum.series().remove(0)
        });
        let scale: f64 = amplitudes.iter().map(|a| f64::from(*a)).sum();
        for (q, value) in series.iter().enumerate() {
            let p = q as f64 - 1.0;
            let direct: f64 = (0..lines)
                .map(|l| {
                    let b = Complex::new(f64::from(phases[l].re), f64::from(phases[l].im)) * f64::from(amplitudes[l]);
                    (b * Complex::from_polar(1.0, 2.0 * PI * l as f64 * p / len as f64 + angle * p)).re
                })
                .sum();
            assert!((value - direct).abs() < 1e-6 * scale, "point {q}: {value} vs {direct}");
        }
    }
}
