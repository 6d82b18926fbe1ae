//! The published spectral model of the across-wind base moment and the base torque of rectangular
//! prisms in boundary-layer flow: the AIJ model after Liang et al. (2002, 2004), as the Taiwan
//! wind code (2018, Eqs. 2.22 and 2.24) and the Thai DPT 1311-50 standard adopted it. The primary
//! sources could not be read here; the constants below were read from three open-source
//! transcriptions of those codes, which agree on every one of them: github.com/chengning6032/CNProject
//! (`Wind_TW/wind_calculations.py`, `calculate_transverse_wind_force` and
//! `calculate_torsional_moment`), github.com/ttwutii/tall_buildings
//! (`my_pages/Wind_For_Tall_Buildings.py`) and a Taiwan 2018 engine's `core/loads/wind.js`.
//! The codes hold them for 3 ≤ H/√(BD) ≤ 6, 0.2 ≤ D/B ≤ 5 and reduced velocities
//! U_H/(f √(BD)) ≤ 10, r = D/B the side ratio (D along the wind, B facing it).
//!
//! - Across-wind: F_L(n) = Σ_j 4κ_j(1 + 0.6β_j)β_j/π · x_j² / ((1 − x_j²)² + 4β_j² x_j²), x_j = n/n_sj,
//!   n = f·B/U_H; κ₁ = 0.85, n_s1 = 0.12/(1 + 0.38 r²)^0.89,
//!   β₁ = (r⁴ + 2.3 r²)/(2.4 r⁴ − 9.2 r³ + 18 r² + 9.5 r − 0.15) + 0.12/r; a second peak for
//!   r ≥ 3: κ₂ = 0.02, n_s2 = 0.56/r^0.85, β₂ = 0.28 r^−0.34. RMS base-moment coefficient
//!   C'_L = 0.0082 r³ − 0.071 r² + 0.22 r.
//! - Torsion: F_T ∝ K_T² U*^{2λ_T}, U* = U_H/(f √(BD)), with K_T and λ_T rational in r, one pair
//!   for U* ≤ 4.5 and one for 6 ≤ U* ≤ 10, log-log interpolation between; RMS base-torque
//!   coefficient C'_T = (0.0066 + 0.015 r²)^0.78.
//!
//! The codes use F at the natural frequency only (the resonant factor π F/(4ζ)); windmeta reads
//! each as the spectrum's shape against frequency, which is what it is. Two closures are windmeta's
//! own and said here: the torsional law holds for U* ≤ 10 only, and at lower frequencies
//! (U* > 10) the spectrum falls in proportion to the frequency from its value at U* = 10 (the
//! torque's own spectrum flattening to a constant, as a stationary process's does); and a spectrum
//! is divided by its area over ln n before use, so that the loads' RMS is the RMS coefficient's
//! (the across-wind model's area is about 0.86: its κ₁ + κ₂).

/// The across-wind model at one side ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct AcrossWindModel {
    /// (κ, n_s, β) of each peak.
    peaks: Vec<[f64; 3]>,
}

impl AcrossWindModel {
    /// The model for side ratio r = D/B.
    pub fn new(side_ratio: f64) -> Self {
        let r = side_ratio;
        let beta1 =
            (r.powi(4) + 2.3 * r * r) / (2.4 * r.powi(4) - 9.2 * r.powi(3) + 18.0 * r * r + 9.5 * r - 0.15) + 0.12 / r;
        let mut peaks = vec![[0.85, 0.12 / (1.0 + 0.38 * r * r).powf(0.89), beta1]];
        if r >= 3.0 {
            peaks.push([0.02, 0.56 / r.powf(0.85), 0.28 * r.powf(-0.34)]);
        }
        AcrossWindModel { peaks }
    }

    /// (κ, n_s, β) of each spectral peak.
    pub fn peaks(&self) -> &[[f64; 3]] {
        &self.peaks
    }

    /// F_L at n = f·B/U_H.
    pub fn value(&self, n: f64) -> f64 {
        self.peaks
            .iter()
            .map(|&[kappa, shedding, beta]| {
                let x2 = (n / shedding).powi(2);
                4.0 * kappa * (1.0 + 0.6 * beta) * beta / std::f64::consts::PI * x2
                    / ((1.0 - x2).powi(2) + 4.0 * beta * beta * x2)
            })
            .sum()
    }

    /// The RMS coefficient of the across-wind base moment, σ_M/(q_H B H²).
    pub fn rms_coefficient(side_ratio: f64) -> f64 {
        let r = side_ratio;
        0.0082 * r.powi(3) - 0.071 * r * r + 0.22 * r
    }
}

/// The reduced velocities between which the torsional model changes its law, and its last.
const TORSION_LOW: f64 = 4.5;
const TORSION_HIGH: f64 = 6.0;
const TORSION_LAST: f64 = 10.0;

/// The torsional model at one side ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct TorsionModel {
    /// √(D/B): the reduced velocity U* = U_H/(f √(BD)) is 1/(n·√(D/B)) for n = f·B/U_H.
    depth_factor: f64,
    /// (K_T, λ_T) for U* ≤ 4.5 and for U* ≥ 6.
    low: [f64; 2],
    high: [f64; 2],
}

impl TorsionModel {
    /// The model for side ratio r = D/B.
    pub fn new(side_ratio: f64) -> Self {
        let r = side_ratio;
        let low = [
            (-1.1 * r + 0.97) / (r * r + 0.85 * r + 3.3) + 0.17,
            (r + 3.6) / (r * r - 5.1 * r + 9.1) + 0.14 / r + 0.14,
        ];
        let high = [
            (0.077 * r - 0.16) / (r * r - 0.96 * r + 0.42) + 0.35 / r + 0.095,
            (0.44 * r * r - 0.0064) / (r.powi(4) - 0.26 * r * r + 0.1) + 0.2,
        ];
        TorsionModel { depth_factor: r.sqrt(), low, high }
    }

    /// K_T² U*^{2λ_T} with the codes' regimes and their log-log bridge (the common factor of the
    /// codes, which the normalisation removes, is left out).
    pub fn law(&self, reduced_velocity: f64) -> f64 {
        let power = |[k, lambda]: [f64; 2], u: f64| k * k * u.powf(2.0 * lambda);
        let u = reduced_velocity;
        if u <= TORSION_LOW {
            power(self.low, u)
        } else if u < TORSION_HIGH {
            let (a, b) = (power(self.low, TORSION_LOW), power(self.high, TORSION_HIGH));
            a * ((u / TORSION_LOW).ln() / (TORSION_HIGH / TORSION_LOW).ln() * (b / a).ln()).exp()
        } else {
            power(self.high, u)
        }
    }

    /// F_T at n = f·B/U_H, up to the codes' constant factor.
    pub fn value(&self, n: f64) -> f64 {
        if n <= 0.0 {
            return 0.0;
        }
        let reduced_velocity = 1.0 / (n * self.depth_factor);
        if reduced_velocity <= TORSION_LAST {
            self.law(reduced_velocity)
        } else {
            self.law(TORSION_LAST) * TORSION_LAST / reduced_velocity
        }
    }

    /// The RMS coefficient of the base torque, σ_T/(q_H B² H).
    pub fn rms_coefficient(side_ratio: f64) -> f64 {
        (0.0066 + 0.015 * side_ratio * side_ratio).powf(0.78)
    }
}
