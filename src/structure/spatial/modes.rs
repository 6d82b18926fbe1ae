//! The modes of a three-dimensional building and how much of each is sway in x, sway in y and
//! twist: a tall building's first modes are often coupled, and which one carries the torsion
//! decides its corner accelerations.

use super::{DOFS_PER_FLOOR, Dof, SpatialStructure, dof};
use crate::error::{Error, Result};
use crate::structure::Modes;
use crate::structure::modes::lowest_eigenpairs;
use faer::Mat;

/// The first modes of a [`SpatialStructure`], each shape scaled so that the roof's largest motion
/// is 1: of its sway in x, its sway in y (m) and its twist times the roof plan's radius of
/// gyration r (the displacement the twist gives a point at r from the centre of mass), whichever
/// is largest in magnitude, taken positive. The modal coordinate y_m is then the roof's dominant
/// motion carried by mode m, in metres, for sway and twist alike.
#[derive(Debug, Clone)]
pub struct SpatialModes {
    /// Natural circular frequencies ω_m (rad/s), ascending.
    pub frequencies: Vec<f64>,
    /// Mode shapes, one column per mode, rows as [`dof`].
    pub shapes: Mat<f64>,
    /// Generalized masses M_m = φ_mᵀ M φ_m (kg).
    pub modal_masses: Vec<f64>,
    /// Each mode's shares of sway in x, sway in y and twist: the parts of φᵀ M φ carried by each
    /// kind of degree of freedom (exact for a diagonal mass; the cross terms of a coupled mass
    /// matrix are left out before the shares are scaled to sum to one).
    pub shares: Vec<[f64; 3]>,
}

impl SpatialModes {
    /// The first `count` modes of `structure` at its reference stiffness and unit mass factor.
    pub fn of(structure: &SpatialStructure, count: usize) -> Result<SpatialModes> {
        Self::solve(structure, count, true)
    }

    /// Every mode of the building, for its classical damping matrix, which does not depend on how a
    /// shape is scaled: a high mode that leaves the roof at rest is scaled to a unit largest
    /// component instead of being refused.
    pub fn all(structure: &SpatialStructure) -> Result<SpatialModes> {
        Self::solve(structure, structure.dofs(), false)
    }

    fn solve(structure: &SpatialStructure, count: usize, roof_must_move: bool) -> Result<SpatialModes> {
        let size = structure.dofs();
        if count == 0 || count > size {
            return Err(Error::invalid(
                "modes",
                format!("must be between 1 and the number of degrees of freedom ({size}), got {count}"),
            ));
        }
        // One more than asked, so that the last mode asked for is aligned with its twin too.
        let solved = (count + 1).min(size);
        let (mut eigenvalues, shapes) = lowest_eigenpairs(&structure.mass, &structure.stiffness, solved)?;
        let mut shapes = shapes;
        align_repeated(&structure.mass, &eigenvalues, &mut shapes);
        let mut shapes = shapes.subcols(0, count).to_owned();
        eigenvalues.truncate(count);
        let roof = structure.floors() - 1;
        let radius = structure.plans[roof].radius_of_gyration();
        let weights = [1.0, 1.0, radius];
        let mut modal_masses = Vec::with_capacity(count);
        let mut shares = Vec::with_capacity(count);
        for m in 0..count {
            let dominant = [Dof::X, Dof::Y, Dof::Rotation]
                .iter()
                .map(|&d| shapes[(dof(roof, d), m)] * weights[d as usize])
                .fold(0.0, |a: f64, b: f64| if b.abs() > a.abs() { b } else { a });
            let largest =
                (0..size).map(|i| shapes[(i, m)]).fold(0.0, |a: f64, b: f64| if b.abs() > a.abs() { b } else { a });
            let scale = if dominant.abs() > 1e-9 * largest.abs() {
                dominant
            } else if roof_must_move {
                return Err(Error::invalid(
                    "modes",
                    format!("mode {} of this structure leaves the roof at rest; retain fewer modes", m + 1),
                ));
            } else {
                largest
            };
            for i in 0..size {
                shapes[(i, m)] /= scale;
            }
            let phi = shapes.col(m);
            modal_masses.push(phi.transpose() * &structure.mass * phi);
            let mut parts = [0.0; DOFS_PER_FLOOR];
            for (d, part) in parts.iter_mut().enumerate() {
                for i in (d..size).step_by(DOFS_PER_FLOOR) {
                    for j in (d..size).step_by(DOFS_PER_FLOOR) {
                        *part += phi[i] * structure.mass[(i, j)] * phi[j];
                    }
                }
            }
            let total: f64 = parts.iter().sum();
            shares.push(parts.map(|p| p / total));
        }
        Ok(SpatialModes { frequencies: eigenvalues.iter().map(|l| l.sqrt()).collect(), shapes, modal_masses, shares })
    }

    /// Number of modes.
    pub fn count(&self) -> usize {
        self.frequencies.len()
    }

    /// The same modes as the reduced-order and full-order integrators take them: shapes over the
    /// degrees of freedom ([`dof`]), frequencies and generalized masses.
    pub fn modes(&self) -> Modes {
        Modes {
            frequencies: self.frequencies.clone(),
            shapes: self.shapes.clone(),
            modal_masses: self.modal_masses.clone(),
        }
    }

    /// Mode m's motion of floor `floor` in direction `d`.
    pub fn at(&self, m: usize, floor: usize, d: Dof) -> f64 {
        self.shapes[(dof(floor, d), m)]
    }
}

/// Modes of one frequency (a symmetric building's sway in x and in y) are any mix of each other
/// as the eigen-solver returns them. Each pair of equal frequencies is turned within its plane to
/// the two mixes with the least and the most sway along x (the eigenvectors of that share's 2 × 2
/// quadratic form over the pair), which keeps the pair M-orthonormal and gives a symmetric
/// building's modes along its axes.
fn align_repeated(mass: &Mat<f64>, eigenvalues: &[f64], shapes: &mut Mat<f64>) {
    let size = shapes.nrows();
    let x_share = |a: usize, b: usize, shapes: &Mat<f64>| -> f64 {
        let mut sum = 0.0;
        for i in (0..size).step_by(DOFS_PER_FLOOR) {
            for j in (0..size).step_by(DOFS_PER_FLOOR) {
                sum += shapes[(i, a)] * mass[(i, j)] * shapes[(j, b)];
            }
        }
        sum
    };
    let mut m = 0;
    while m + 1 < eigenvalues.len() {
        if (eigenvalues[m + 1] - eigenvalues[m]).abs() > 1e-9 * eigenvalues[m] {
            m += 1;
            continue;
        }
        // The rotation by α that diagonalises [[p, q], [q, r]]: tan 2α = 2q / (p − r); the first
        // column then holds the larger share of x.
        let (p, q, r) = (x_share(m, m, shapes), x_share(m, m + 1, shapes), x_share(m + 1, m + 1, shapes));
        let alpha = 0.5 * (2.0 * q).atan2(p - r);
        let (sin, cos) = alpha.sin_cos();
        for i in 0..size {
            let (a, b) = (shapes[(i, m)], shapes[(i, m + 1)]);
            shapes[(i, m)] = cos * a + sin * b;
            shapes[(i, m + 1)] = -sin * a + cos * b;
        }
        m += 2;
    }
}
