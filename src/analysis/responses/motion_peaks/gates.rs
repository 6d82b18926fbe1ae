//! Which chunks and steps of a block could raise a floor's peak acceleration, told with few
//! powers: the tests ahead of the exact evaluation in [`super::reduce_acceleration`].

use super::BOUND_MARGIN;
use crate::simd::{LANES, Lanes};

/// Whether a chunk's or a step's |L| and S = Σ_m K_m|ŷ'_m| could beat a lane's running peak,
/// (1 + ε)(|L| + P S^α) > best, told without a power per test: |L| is placed on a grid of
/// [`GATE_BINS`] intervals of best/(1 + ε), and S compared with the speed that the interval's top
/// leaves room for, ((1 − (j + 1)/B) best/((1 + ε) P))^{1/α}. Conservative (it lets through a
/// little more than the bound would), and recomputed only when the peak rises: with one power,
/// since every speed of the table is (best/((1 + ε) P))^{1/α} times a fraction of [`Fractions`].
#[derive(Clone, Copy)]
pub(super) struct Gate {
    best: f64,
    reach: f64,
    /// B/reach: a multiplication places |L| on the grid (a division cost more than the rest of the
    /// test; the bound's margin covers the rounding either way).
    bins_per_reach: f64,
    slow: [f64; GATE_BINS + 1],
}

/// Every lane's [`Gate`], and a test of all lanes at once that comes first: for α < 1, P S^α lies
/// below its tangents at the speeds S_t where P S_t^α = f_t best/(1 + ε), so a chunk with
/// |L| + min_t (a_t + b_t S) ≤ best/(1 + ε) cannot beat the peak (a_t = (1 − α) f_t best/(1 + ε),
/// b_t = α f_t best/((1 + ε) S_t)); a few multiply-adds for eight lanes rule out most chunks.
/// For α ≥ 1 (convex, no tangent above it) every lane is let through to its gate.
pub(super) struct Gates {
    pub(super) lanes: [Gate; LANES],
    fractions: Fractions,
    reach: Lanes,
    offsets: [Lanes; TANGENTS.len()],
    slopes: [Lanes; TANGENTS.len()],
}

/// The fractions f_t of the running peak at whose speeds the tangents touch.
const TANGENTS: [f64; 5] = [1.0, 0.6, 0.3, 0.12, 0.04];

impl Default for Gates {
    fn default() -> Self {
        let pass = [f64::INFINITY; LANES];
        Gates {
            lanes: [Gate::default(); LANES],
            fractions: Fractions::default(),
            reach: [0.0; LANES],
            offsets: [pass; TANGENTS.len()],
            slopes: [[0.0; LANES]; TANGENTS.len()],
        }
    }
}

impl Gates {
    /// Lane l's gate and tangents for its running peak `best` and the bound's P and α.
    pub(super) fn open_to(&mut self, l: usize, best: f64, p: f64, alpha: f64) {
        if best == self.lanes[l].best {
            return;
        }
        if self.fractions.alpha != alpha {
            self.fractions = Fractions::new(alpha);
        }
        let fractions = &self.fractions;
        let speed = self.lanes[l].open_to(best, p, alpha, fractions);
        let reach = self.lanes[l].reach;
        self.reach[l] = reach;
        for (t, (f, fraction)) in TANGENTS.iter().zip(&fractions.tangents).enumerate() {
            let (offset, slope) = if p == 0.0 {
                (0.0, 0.0)
            } else if alpha < 1.0 && reach > 0.0 {
                ((1.0 - alpha) * f * reach, alpha * f * reach / (speed * fraction))
            } else {
                (f64::INFINITY, 0.0)
            };
            self.offsets[t][l] = offset;
            self.slopes[t][l] = slope;
        }
    }

    /// An upper bound on P S^α in lane l without a power: the lowest tangent (α < 1, concave);
    /// infinite where there are no tangents (α ≥ 1).
    #[inline(always)]
    pub(super) fn damper_bound(&self, l: usize, speed: f64) -> f64 {
        self.offsets.iter().zip(&self.slopes).fold(f64::INFINITY, |m, (o, s)| m.min(s[l].mul_add(speed, o[l])))
    }

    /// The lanes (bit l) whose peak a chunk with these |L| and S bounds could beat.
    #[inline(always)]
    pub(super) fn lanes_that_may_beat(&self, linear: &Lanes, speed: &Lanes) -> u8 {
        let mut damper = [f64::INFINITY; LANES];
        for (offset, slope) in self.offsets.iter().zip(&self.slopes) {
            (0..LANES).for_each(|l| damper[l] = damper[l].min(slope[l].mul_add(speed[l], offset[l])));
        }
        // NaN lets a lane through, to be looked at.
        (0..LANES).fold(0, |mask, l| {
            let most = linear[l] + damper[l];
            mask | (u8::from(most > self.reach[l] || most.is_nan()) << l)
        })
    }
}

/// Intervals of |L| in a [`Gate`].
const GATE_BINS: usize = 64;

/// The powers 1/α of the fractions of the running peak that a [`Gate`]'s speeds and the tangents'
/// touching speeds leave to the dampers, (1 − j/B)^{1/α} and f_t^{1/α}: computed once per damper
/// law, so that opening a gate takes one power instead of one per interval and tangent.
#[derive(Clone, Copy)]
struct Fractions {
    alpha: f64,
    bins: [f64; GATE_BINS + 1],
    tangents: [f64; TANGENTS.len()],
}

impl Default for Fractions {
    fn default() -> Self {
        Fractions { alpha: f64::NAN, bins: [0.0; GATE_BINS + 1], tangents: [0.0; TANGENTS.len()] }
    }
}

impl Fractions {
    fn new(alpha: f64) -> Self {
        Fractions {
            alpha,
            bins: std::array::from_fn(|j| (1.0 - j as f64 / GATE_BINS as f64).powf(1.0 / alpha)),
            tangents: TANGENTS.map(|f| f.powf(1.0 / alpha)),
        }
    }
}

impl Default for Gate {
    fn default() -> Self {
        Gate { best: f64::NAN, reach: 0.0, bins_per_reach: 0.0, slow: [0.0; GATE_BINS + 1] }
    }
}

impl Gate {
    /// The gate for a running peak `best` and the bound's P and α: the speed (reach/P)^{1/α} at
    /// which the dampers alone could reach the peak.
    fn open_to(&mut self, best: f64, p: f64, alpha: f64, fractions: &Fractions) -> f64 {
        self.best = best;
        self.reach = best / (1.0 + BOUND_MARGIN);
        self.bins_per_reach = GATE_BINS as f64 / self.reach;
        let speed = if p > 0.0 { (self.reach / p).powf(1.0 / alpha) } else { f64::INFINITY };
        for (slow, fraction) in self.slow.iter_mut().zip(&fractions.bins) {
            // The top interval leaves no room (fraction 0): a speed of 0 even where `speed`
            // overflowed, where the product would be NaN and let nothing through.
            *slow = match (p > 0.0, *fraction == 0.0) {
                (false, _) => f64::INFINITY,
                (true, true) => 0.0,
                (true, false) => speed * fraction,
            };
        }
        speed
    }

    #[inline(always)]
    pub(super) fn may_beat(&self, linear: f64, speed: f64) -> bool {
        if linear >= self.reach || linear.is_nan() {
            return true;
        }
        let j = (linear * self.bins_per_reach) as usize;
        speed > self.slow[(j + 1).min(GATE_BINS)]
    }
}
