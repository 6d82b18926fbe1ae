//! Three-dimensional stiffness from planar parts. A rigid floor moves a point (p_x, p_y) of its
//! plan (from its centre of mass) by (u_x − θ p_y, u_y + θ p_x), so a planar lateral system — a
//! frame, a wall line, a storey's lumped shear stiffness — whose line runs along direction
//! (cos β, sin β) through that point sees the floor's motion d_j = w_j·(u_x, u_y, θ)_j with
//! w = (cos β, sin β, sin β p_x − cos β p_y). Its condensed lateral stiffness K₂ (one row per
//! floor) then adds Tᵀ K₂ T to the building's, T_{j,3j+d} = w_{j,d}: the same transformation a
//! rigid-diaphragm finite-element model applies to each of its frames.

use super::{DOFS_PER_FLOOR, Dof, FloorPlan, PlanDamper, SpatialStructure, dof};
use crate::error::{Error, Result, require_finite, require_positive};
use faer::Mat;

/// A planar lateral system: its condensed stiffness over the floors and the line it acts along.
#[derive(Debug, Clone)]
pub struct PlanarSystem {
    /// Condensed lateral stiffness (N/m), one row per floor, at the building's reference modulus.
    pub stiffness: Mat<f64>,
    /// The unit vector along its line on the plan, (cos β, sin β) with β counter-clockwise from x.
    pub direction: [f64; 2],
    /// A point of its line, from the plan's centre (m).
    pub position: [f64; 2],
}

impl PlanarSystem {
    /// Its weights on each floor's (u_x, u_y, θ) about the floors' centres of mass.
    fn weights(&self, centres_of_mass: &[[f64; 2]]) -> Vec<[f64; 3]> {
        let [cos, sin] = self.direction;
        centres_of_mass
            .iter()
            .map(|c| {
                let (x, y) = (self.position[0] - c[0], self.position[1] - c[1]);
                [cos, sin, sin * x - cos * y]
            })
            .collect()
    }
}

/// The building's stiffness over three degrees of freedom per floor: Σ Tᵀ K₂ T over `systems`.
pub fn assemble(systems: &[PlanarSystem], centres_of_mass: &[[f64; 2]]) -> Result<Mat<f64>> {
    let floors = centres_of_mass.len();
    let mut stiffness = Mat::zeros(DOFS_PER_FLOOR * floors, DOFS_PER_FLOOR * floors);
    for (s, system) in systems.iter().enumerate() {
        if system.stiffness.nrows() != floors || system.stiffness.ncols() != floors {
            return Err(Error::invalid(
                format!("systems[{s}].stiffness"),
                format!("must be {floors}×{floors}, got {}×{}", system.stiffness.nrows(), system.stiffness.ncols()),
            ));
        }
        add_planar(&mut stiffness, &system.stiffness, &system.weights(centres_of_mass));
    }
    Ok(stiffness)
}

/// Adds Tᵀ K₂ T to `stiffness`, T's row j holding `weights[j]` at floor j's degrees of freedom.
fn add_planar(stiffness: &mut Mat<f64>, planar: &Mat<f64>, weights: &[[f64; 3]]) {
    let floors = weights.len();
    for i in 0..floors {
        for j in 0..floors {
            let k = planar[(i, j)];
            if k == 0.0 {
                continue;
            }
            for a in 0..DOFS_PER_FLOOR {
                for b in 0..DOFS_PER_FLOOR {
                    stiffness[(DOFS_PER_FLOOR * i + a, DOFS_PER_FLOOR * j + b)] += weights[i][a] * k * weights[j][b];
                }
            }
        }
    }
}

/// One storey of a building described floor by floor: the floor's mass and its moment of inertia,
/// and the storey below it as a shear storey in each direction and in torsion, about the plan's
/// centre (the centre of stiffness); the centre of mass may lie away from it.
#[derive(Debug, Clone, PartialEq)]
pub struct StoreyProperties {
    /// Elevation of the floor (m).
    pub elevation: f64,
    /// The floor's plan.
    pub plan: FloorPlan,
    /// The floor's mass (kg).
    pub mass: f64,
    /// Its moment of inertia about the vertical axis through its centre of mass (kg·m²); `None`
    /// for a floor whose mass is spread evenly over its plan, m (B² + D²)/12.
    pub moment_of_inertia: Option<f64>,
    /// Where its centre of mass is, from the plan's centre (m).
    pub centre_of_mass: [f64; 2],
    /// Shear stiffness of the storey below, along x (N/m).
    pub stiffness_x: f64,
    /// Shear stiffness of the storey below, along y (N/m).
    pub stiffness_y: f64,
    /// Torsional stiffness of the storey below about the plan's centre (N·m/rad).
    pub torsional_stiffness: f64,
}

/// A building of shear storeys (the second way of describing one): stiffness in x, y and torsion
/// acting at each plan's centre, mass at each floor's centre of mass.
pub fn from_storeys(
    storeys: &[StoreyProperties],
    reference_youngs_modulus: f64,
    dampers: Vec<PlanDamper>,
) -> Result<SpatialStructure> {
    for (j, storey) in storeys.iter().enumerate() {
        require_positive(&format!("storeys[{j}].mass_kg"), storey.mass)?;
        if let Some(inertia) = storey.moment_of_inertia {
            require_positive(&format!("storeys[{j}].moment_of_inertia_kg_m2"), inertia)?;
        }
        require_positive(&format!("storeys[{j}].stiffness_x_n_per_m"), storey.stiffness_x)?;
        require_positive(&format!("storeys[{j}].stiffness_y_n_per_m"), storey.stiffness_y)?;
        require_positive(&format!("storeys[{j}].torsional_stiffness_n_m_per_rad"), storey.torsional_stiffness)?;
        require_finite(&format!("storeys[{j}].centre_of_mass[0]"), storey.centre_of_mass[0])?;
        require_finite(&format!("storeys[{j}].centre_of_mass[1]"), storey.centre_of_mass[1])?;
    }
    let centres: Vec<[f64; 2]> = storeys.iter().map(|s| s.centre_of_mass).collect();
    let lines = [
        ([1.0, 0.0], storeys.iter().map(|s| s.stiffness_x).collect::<Vec<_>>()),
        ([0.0, 1.0], storeys.iter().map(|s| s.stiffness_y).collect()),
    ];
    let systems: Vec<PlanarSystem> = lines
        .into_iter()
        .map(|(direction, storey_stiffness)| PlanarSystem {
            stiffness: shear_building(&storey_stiffness),
            direction,
            position: [0.0, 0.0],
        })
        .collect();
    let mut stiffness = assemble(&systems, &centres)?;
    let torsion = shear_building(&storeys.iter().map(|s| s.torsional_stiffness).collect::<Vec<_>>());
    add_planar(&mut stiffness, &torsion, &vec![[0.0, 0.0, 1.0]; storeys.len()]);
    let floors = storeys.len();
    let mut mass = Mat::zeros(DOFS_PER_FLOOR * floors, DOFS_PER_FLOOR * floors);
    for (j, storey) in storeys.iter().enumerate() {
        let inertia = storey.moment_of_inertia.unwrap_or(storey.mass * storey.plan.radius_of_gyration().powi(2));
        mass[(dof(j, Dof::X), dof(j, Dof::X))] = storey.mass;
        mass[(dof(j, Dof::Y), dof(j, Dof::Y))] = storey.mass;
        mass[(dof(j, Dof::Rotation), dof(j, Dof::Rotation))] = inertia;
    }
    SpatialStructure::new(
        stiffness,
        mass,
        storeys.iter().map(|s| s.elevation).collect(),
        storeys.iter().map(|s| s.plan).collect(),
        centres,
        reference_youngs_modulus,
        dampers,
    )
}

/// The stiffness of shear storeys stacked from the ground: storey j (below floor j) joins floor j
/// to floor j − 1 (the ground for j = 0).
fn shear_building(storey_stiffness: &[f64]) -> Mat<f64> {
    let n = storey_stiffness.len();
    let mut k = Mat::zeros(n, n);
    for (j, &kj) in storey_stiffness.iter().enumerate() {
        k[(j, j)] += kj;
        if j > 0 {
            k[(j - 1, j - 1)] += kj;
            k[(j, j - 1)] -= kj;
            k[(j - 1, j)] -= kj;
        }
    }
    k
}
