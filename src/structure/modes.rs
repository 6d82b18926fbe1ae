//! Generalized eigen-analysis K φ = ω² M φ and the modal quantities of the reduced model (Eq. 4).
//!
//! faer has no symmetric-definite generalized solver, so the problem is reduced to a standard one:
//! M = L Lᵀ, C = L⁻¹ K L⁻ᵀ, C ψ = ω² ψ, φ = L⁻ᵀ ψ.

use super::Structure;
use crate::error::{Error, Result};
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Mat, Par, Side};

/// The first modes of a structure, shapes normalised to a unit roof component so that the modal
/// coordinate y_m is the roof displacement carried by mode m.
#[derive(Debug, Clone)]
pub struct Modes {
    /// Natural circular frequencies ω_m (rad/s), ascending.
    pub frequencies: Vec<f64>,
    /// Mode shapes, one column per mode (floors × modes), roof component 1.
    pub shapes: Mat<f64>,
    /// Generalized masses M_m = φ_mᵀ M φ_m (kg).
    pub modal_masses: Vec<f64>,
}

/// How mode shapes are scaled.
#[derive(Clone, Copy)]
enum Normalisation {
    /// Unit roof component: the modal coordinate is the roof displacement the mode carries.
    Roof,
    /// Unit roof component, or unit largest component for a mode that leaves the roof at rest.
    RoofWhereItMoves,
}

impl Modes {
    /// The first `count` modes of `structure` at its reference stiffness and unit mass factor,
    /// every one roof-normalised (a mode that does not move the roof is refused).
    pub fn of(structure: &Structure, count: usize) -> Result<Modes> {
        Self::solve(structure, count, Normalisation::Roof)
    }

    /// All the structure's modes for its classical damping matrix, which does not depend on how a
    /// shape is scaled: roof-normalised where the roof moves, else to a unit largest component (a
    /// high mode of a building whose storeys stiffen downwards can leave the roof at rest, and must
    /// not refuse a study that retains three modes).
    pub fn all(structure: &Structure) -> Result<Modes> {
        Self::solve(structure, structure.floors(), Normalisation::RoofWhereItMoves)
    }

    fn solve(structure: &Structure, count: usize, normalisation: Normalisation) -> Result<Modes> {
        let n = structure.floors();
        if count == 0 || count > n {
            return Err(Error::invalid(
                "modes",
                format!("must be between 1 and the number of floors ({n}), got {count}"),
            ));
        }
        let (eigenvalues, mut shapes) = lowest_eigenpairs(&structure.mass, &structure.stiffness, count)?;
        let roof = n - 1;
        let mut frequencies = Vec::with_capacity(count);
        let mut modal_masses = Vec::with_capacity(count);
        for (m, &lambda) in eigenvalues.iter().enumerate() {
            let largest =
                (0..n).map(|i| shapes[(i, m)]).fold(0.0, |a: f64, b: f64| if b.abs() > a.abs() { b } else { a });
            let mut r = shapes[(roof, m)];
            if r.abs() < 1e-9 * largest.abs() {
                match normalisation {
                    Normalisation::Roof => {
                        return Err(Error::invalid(
                            "modes",
                            format!(
                                "mode {} of this structure does not move the roof, so it cannot be roof-normalised; \
                                 retain fewer modes",
                                m + 1
                            ),
                        ));
                    }
                    Normalisation::RoofWhereItMoves => r = largest,
                }
            }
            for i in 0..n {
                shapes[(i, m)] /= r;
            }
            let phi = shapes.col(m);
            let mass = phi.transpose() * &structure.mass * phi;
            frequencies.push(lambda.sqrt());
            modal_masses.push(mass);
        }
        Ok(Modes { frequencies, shapes, modal_masses })
    }

    /// Number of modes.
    pub fn count(&self) -> usize {
        self.frequencies.len()
    }

    /// The modes of the same structure with stiffness × `stiffness_factor` and mass × `mass_factor`:
    /// shapes unchanged, ω scaled by √(stiffness/mass), generalized masses by the mass factor.
    pub fn scaled(&self, stiffness_factor: f64, mass_factor: f64) -> Modes {
        let ratio = (stiffness_factor / mass_factor).sqrt();
        Modes {
            frequencies: self.frequencies.iter().map(|w| w * ratio).collect(),
            shapes: self.shapes.clone(),
            modal_masses: self.modal_masses.iter().map(|m| m * mass_factor).collect(),
        }
    }

    /// Natural periods T_m = 2π/ω_m (s).
    pub fn periods(&self) -> Vec<f64> {
        self.frequencies.iter().map(|w| 2.0 * std::f64::consts::PI / w).collect()
    }
}

/// The `count` lowest eigenvalues ω² of K φ = ω² M φ, ascending, and their shapes (columns,
/// M-orthonormal); refuses a mass that is not positive definite and a non-positive eigenvalue.
pub(super) fn lowest_eigenpairs(mass: &Mat<f64>, stiffness: &Mat<f64>, count: usize) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = mass.nrows();
    let llt = mass.llt(Side::Lower).map_err(|_| Error::invalid("mass", "must be positive definite"))?;
    let l = llt.L();
    // C = L⁻¹ K L⁻ᵀ: solve L X = K, then L Cᵀ = Xᵀ.
    let mut x = stiffness.clone();
    solve_lower_triangular_in_place(l, x.as_mut(), Par::Seq);
    let mut c = x.transpose().to_owned();
    solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let eigen =
        c.self_adjoint_eigen(Side::Lower).map_err(|_| Error::Numerical("the eigen-solver did not converge".into()))?;
    let eigenvalues: Vec<f64> = (0..count).map(|m| eigen.S()[m]).collect();
    if eigenvalues.iter().any(|&lambda| lambda <= 0.0) {
        return Err(Error::invalid("stiffness", "must be positive definite (a non-positive eigenvalue appeared)"));
    }
    let mut shapes = eigen.U().subcols(0, count).to_owned();
    solve_upper_triangular_in_place(l.transpose(), shapes.as_mut(), Par::Seq);
    Ok((eigenvalues, shapes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two equal masses on two equal springs (a shear building): ω² = (k/m)(3 ∓ √5)/2 and the
    /// shapes' ratio is known in closed form.
    #[test]
    fn two_storey_shear_building_matches_closed_form() {
        let (k, m) = (2.0e6, 1.0e3);
        let stiffness = Mat::from_fn(2, 2, |i, j| match (i, j) {
            (0, 0) => 2.0 * k,
            (1, 1) => k,
            _ => -k,
        });
        let mass = Mat::from_fn(2, 2, |i, j| if i == j { m } else { 0.0 });
        let s = Structure::new(stiffness, mass, vec![3.0, 6.0], vec![1.0, 1.0], 1.0, vec![]).unwrap();
        let modes = Modes::of(&s, 2).unwrap();
        let five = 5f64.sqrt();
        let w1 = ((k / m) * (3.0 - five) / 2.0).sqrt();
        let w2 = ((k / m) * (3.0 + five) / 2.0).sqrt();
        assert!((modes.frequencies[0] / w1 - 1.0).abs() < 1e-12);
        assert!((modes.frequencies[1] / w2 - 1.0).abs() < 1e-12);
        // First mode: φ = ((√5 − 1)/2, 1); generalized mass m(φ₁² + 1).
        let phi1 = (five - 1.0) / 2.0;
        assert!((modes.shapes[(0, 0)] - phi1).abs() < 1e-12);
        assert!((modes.shapes[(1, 0)] - 1.0).abs() < 1e-15);
        assert!((modes.modal_masses[0] / (m * (phi1 * phi1 + 1.0)) - 1.0).abs() < 1e-12);
        let scaled = modes.scaled(4.0, 1.0);
        assert!((scaled.frequencies[0] / (2.0 * w1) - 1.0).abs() < 1e-12);
    }
}
