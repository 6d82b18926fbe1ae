//! The horizontal acceleration occupants feel at the corners of a floor plate, the quantity of
//! comfort criteria for tall buildings: the resultant of the floor's two sways and its twist at the
//! plan's corners, where the twist adds most.

use super::FloorPlan;

/// The worst corner of one floor over a history: the largest resultant acceleration and the
/// largest RMS of it, each with its corner (index into [`FloorPlan::corners`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CornerAcceleration {
    /// max over corners and time of |a| (m/s²).
    pub peak: f64,
    /// The corner of the peak.
    pub peak_corner: usize,
    /// max over corners of √(mean |a|²) (m/s²).
    pub rms: f64,
    /// The corner of the largest RMS.
    pub rms_corner: usize,
}

/// The corner accelerations of a floor of plan `plan` whose centre of mass lies at `centre_of_mass`
/// from the plan's centre, from the histories of its accelerations along x and y (m/s²) and in
/// twist (rad/s²) at the centre of mass: a point at p from the centre of mass accelerates by
/// (ẍ − θ̈ p_y, ÿ + θ̈ p_x). The peak looks at every step, the RMS at every `rms_stride`-th from
/// the first (as a floor's RMS acceleration samples the storm). Empty histories give zeros.
pub fn corner_acceleration(
    plan: &FloorPlan,
    centre_of_mass: [f64; 2],
    x: &[f64],
    y: &[f64],
    rotation: &[f64],
    rms_stride: usize,
) -> CornerAcceleration {
    let mut worst = CornerAcceleration { peak: 0.0, peak_corner: 0, rms: 0.0, rms_corner: 0 };
    let steps = x.len().min(y.len()).min(rotation.len());
    let stride = rms_stride.max(1);
    for (k, corner) in plan.corners().iter().enumerate() {
        let (px, py) = (corner[0] - centre_of_mass[0], corner[1] - centre_of_mass[1]);
        let (mut peak_square, mut sum_square, mut sampled) = (0.0f64, 0.0, 0usize);
        for t in 0..steps {
            let (ax, ay) = (x[t] - rotation[t] * py, y[t] + rotation[t] * px);
            let square = ax * ax + ay * ay;
            peak_square = peak_square.max(square);
            if t % stride == 0 {
                sum_square += square;
                sampled += 1;
            }
        }
        let rms = if sampled > 0 { (sum_square / sampled as f64).sqrt() } else { 0.0 };
        let peak = peak_square.sqrt();
        if peak > worst.peak {
            (worst.peak, worst.peak_corner) = (peak, k);
        }
        if rms > worst.rms {
            (worst.rms, worst.rms_corner) = (rms, k);
        }
    }
    worst
}

/// The resultant horizontal acceleration (m/s²) at corner `corner` (an index into
/// [`FloorPlan::corners`]) step by step, from the same histories as [`corner_acceleration`].
pub fn corner_history(
    plan: &FloorPlan,
    centre_of_mass: [f64; 2],
    [x, y, rotation]: [&[f64]; 3],
    corner: usize,
) -> Vec<f64> {
    let at = plan.corners()[corner.min(3)];
    let (px, py) = (at[0] - centre_of_mass[0], at[1] - centre_of_mass[1]);
    x.iter().zip(y).zip(rotation).map(|((ax, ay), r)| (ax - r * py).hypot(ay + r * px)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const PLAN: FloorPlan = FloorPlan { breadth: 30.0, depth: 40.0 };

    fn wave(amplitude: f64, omega: f64) -> Vec<f64> {
        (0..2000).map(|t| amplitude * (omega * t as f64 * 0.01).sin()).collect()
    }

    #[test]
    fn a_twist_alone_moves_every_corner_by_its_distance() {
        // Centre of mass at the centre: every corner is 25 m away; |a| = 25·|θ̈|.
        let zero = vec![0.0; 2000];
        let twist = wave(0.002, 1.3);
        let result = corner_acceleration(&PLAN, [0.0, 0.0], &zero, &zero, &twist, 1);
        let peak = twist.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let rms = (twist.iter().map(|v| v * v).sum::<f64>() / 2000.0).sqrt();
        assert!((result.peak - 25.0 * peak).abs() < 1e-12);
        assert!((result.rms - 25.0 * rms).abs() < 1e-12);
        // Off-centre mass: the farthest corner from it governs, (−15, −20) from (3, 4): 30 m.
        let result = corner_acceleration(&PLAN, [3.0, 4.0], &zero, &zero, &twist, 1);
        assert_eq!(result.peak_corner, 2);
        assert!((result.peak - 30.0 * peak).abs() < 1e-12);
    }

    #[test]
    fn sway_and_twist_add_at_the_corner_they_share() {
        // ẍ = A sin, θ̈ = −(A/20) sin: at corners with p_y = +20 the twist doubles ẍ, at p_y = −20 it
        // cancels it, and both see ÿ = ±15·θ̈.
        let a = 0.05;
        let x = wave(a, 0.9);
        let twist: Vec<f64> = x.iter().map(|v| -v / 20.0).collect();
        let zero = vec![0.0; 2000];
        let result = corner_acceleration(&PLAN, [0.0, 0.0], &x, &zero, &twist, 1);
        let peak = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let expected = peak * (4.0f64 + (15.0f64 / 20.0).powi(2)).sqrt();
        assert!([0, 1].contains(&result.peak_corner), "corner {}", result.peak_corner);
        assert!((result.peak - expected).abs() < 1e-12 * expected, "{} against {expected}", result.peak);
    }
}
