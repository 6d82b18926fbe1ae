//! Buildings that move in two directions and twist: three degrees of freedom per floor, the two
//! horizontal translations and the rotation about the vertical axis, taken at the floor's centre
//! of mass (so that the mass matrix of rigid floors is diagonal); the floor plans the wind acts on
//! and whose corners the occupants feel; dampers placed on the plan with their direction.
//!
//! Degrees of freedom are numbered floor by floor from the ground up, x, y, θ within a floor
//! (index 3j + d, [`dof`]), the order in which a finite-element program condenses rigid
//! diaphragms. Lengths on a plan are measured from the plan's geometric centre, x along its
//! breadth, y along its depth, θ counter-clockwise seen from above: a point at (p_x, p_y) from the
//! centre of mass moves by (u_x − θ p_y, u_y + θ p_x).

mod assembly;
mod corner;
mod custom;
mod frame40;
mod modes;

pub use assembly::{PlanarSystem, StoreyProperties, assemble, from_storeys};
pub use corner::{CornerAcceleration, corner_acceleration, corner_history};
pub use custom::{CustomPlan, CustomPlanDamper, CustomSpatialStructure, CustomStorey};
pub use frame40::{FRAME40_3D_PLAN, frame40_3d};
pub use modes::SpatialModes;

use super::{DamperPlacement, check_positive_definite, check_square_symmetric};
use crate::error::{Error, Result, require_finite, require_positive};
use faer::Mat;

/// Degrees of freedom per floor: x, y, θ.
pub const DOFS_PER_FLOOR: usize = 3;

/// A direction of motion on a floor, as requests name it: `x`, `y` or `rotation`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Dof {
    /// Sway along the plan's x axis (m).
    X = 0,
    /// Sway along the plan's y axis (m).
    Y = 1,
    /// Twist about the vertical axis through the centre of mass, counter-clockwise (rad).
    Rotation = 2,
}

/// The index of floor `floor`'s degree of freedom `d` (0-based floor).
pub fn dof(floor: usize, d: Dof) -> usize {
    DOFS_PER_FLOOR * floor + d as usize
}

/// A floor's rectangular plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorPlan {
    /// Breadth along x (m).
    pub breadth: f64,
    /// Depth along y (m).
    pub depth: f64,
}

impl FloorPlan {
    /// Radius of gyration of a uniform plate of this plan about its centre, √((B² + D²)/12) (m):
    /// I_z = m r² for a floor whose mass is spread evenly.
    pub fn radius_of_gyration(&self) -> f64 {
        ((self.breadth * self.breadth + self.depth * self.depth) / 12.0).sqrt()
    }

    /// The four corners, from the plan's centre (m), counter-clockwise from (+B/2, +D/2).
    pub fn corners(&self) -> [[f64; 2]; 4] {
        let (b, d) = (0.5 * self.breadth, 0.5 * self.depth);
        [[b, d], [-b, d], [-b, -d], [b, -d]]
    }

    /// Whether a point (from the centre) lies on the plan or its edge.
    fn holds(&self, point: [f64; 2]) -> bool {
        let slack = 1e-9 * self.breadth.max(self.depth);
        point[0].abs() <= 0.5 * self.breadth + slack && point[1].abs() <= 0.5 * self.depth + slack
    }
}

/// A damper between two consecutive floors (or the ground and the first floor), acting along a
/// direction of the plan at a point of it; its axial velocity is cos θ times the two floors'
/// relative velocity at that point along that direction.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanDamper {
    /// Its floors, brace angle and coefficient group, as in a plane frame.
    pub placement: DamperPlacement,
    /// The unit vector it acts along on the plan, (cos β, sin β) with β counter-clockwise from x
    /// ([`plan_direction`] from degrees).
    pub direction: [f64; 2],
    /// Where it sits on the plan, from the plan's centre (m).
    pub position: [f64; 2],
}

impl PlanDamper {
    /// The horizontal motion of the damper's point along its direction, per unit of a floor's
    /// (u_x, u_y, θ) about a centre of mass at `centre_of_mass` (from the plan's centre): its lever
    /// arm in torsion is the third weight.
    pub fn weights(&self, centre_of_mass: [f64; 2]) -> [f64; 3] {
        let [cos, sin] = self.direction;
        let (x, y) = (self.position[0] - centre_of_mass[0], self.position[1] - centre_of_mass[1]);
        [cos, sin, sin * x - cos * y]
    }
}

/// The model of a building with rigid floors: mass and stiffness over three degrees of freedom per
/// floor, floor plans, where each floor's centre of mass is, and the dampers.
#[derive(Debug, Clone)]
pub struct SpatialStructure {
    /// Stiffness (N/m, N·m/rad and N/rad) over [`dof`] at the reference Young's modulus.
    pub stiffness: Mat<f64>,
    /// Mass (kg, kg·m²) over [`dof`] at mass factor 1.
    pub mass: Mat<f64>,
    /// Elevation of each floor above the ground (m).
    pub floor_elevations: Vec<f64>,
    /// Each floor's plan.
    pub plans: Vec<FloorPlan>,
    /// Each floor's centre of mass, from its plan's centre (m): the origin of its degrees of freedom.
    pub centres_of_mass: Vec<[f64; 2]>,
    /// The Young's modulus (Pa) at which `stiffness` holds; an uncertain modulus scales it.
    pub reference_youngs_modulus: f64,
    /// The dampers; may be empty.
    pub dampers: Vec<PlanDamper>,
}

impl SpatialStructure {
    /// Checks every invariant and builds the structure; errors name the offending field.
    pub fn new(
        stiffness: Mat<f64>,
        mass: Mat<f64>,
        floor_elevations: Vec<f64>,
        plans: Vec<FloorPlan>,
        centres_of_mass: Vec<[f64; 2]>,
        reference_youngs_modulus: f64,
        dampers: Vec<PlanDamper>,
    ) -> Result<Self> {
        let floors = floor_elevations.len();
        if floors == 0 {
            return Err(Error::invalid("floor_elevations_m", "at least one floor is needed"));
        }
        let size = DOFS_PER_FLOOR * floors;
        check_square_symmetric("stiffness", &stiffness, size)?;
        check_square_symmetric("mass", &mass, size)?;
        check_positive_definite("stiffness", &stiffness)?;
        check_positive_definite("mass", &mass)?;
        super::check_elevations(&floor_elevations)?;
        per_floor("plans", plans.len(), floors)?;
        per_floor("centres_of_mass", centres_of_mass.len(), floors)?;
        for (j, plan) in plans.iter().enumerate() {
            require_positive(&format!("plans[{j}].breadth_m"), plan.breadth)?;
            require_positive(&format!("plans[{j}].depth_m"), plan.depth)?;
            let centre = centres_of_mass[j];
            require_finite(&format!("centres_of_mass[{j}][0]"), centre[0])?;
            require_finite(&format!("centres_of_mass[{j}][1]"), centre[1])?;
            if !plan.holds(centre) {
                return Err(Error::invalid(
                    format!("centres_of_mass[{j}]"),
                    format!(
                        "({}, {}) m lies outside the floor's {} × {} m plan",
                        centre[0], centre[1], plan.breadth, plan.depth
                    ),
                ));
            }
        }
        require_positive("reference_youngs_modulus", reference_youngs_modulus)?;
        let placements: Vec<DamperPlacement> = dampers.iter().map(|d| d.placement.clone()).collect();
        super::check_dampers(&placements, floors)?;
        for (k, d) in dampers.iter().enumerate() {
            check_direction(&format!("dampers[{k}].direction"), d.direction)?;
            let floor = d.placement.upper_floor;
            let plan = &plans[floor];
            if !(d.position.iter().all(|p| p.is_finite()) && plan.holds(d.position)) {
                return Err(Error::invalid(
                    format!("dampers[{k}].position"),
                    format!(
                        "({}, {}) m lies outside floor {}'s {} × {} m plan",
                        d.position[0],
                        d.position[1],
                        floor + 1,
                        plan.breadth,
                        plan.depth
                    ),
                ));
            }
        }
        Ok(SpatialStructure {
            stiffness,
            mass,
            floor_elevations,
            plans,
            centres_of_mass,
            reference_youngs_modulus,
            dampers,
        })
    }

    /// Number of floors.
    pub fn floors(&self) -> usize {
        self.floor_elevations.len()
    }

    /// Number of degrees of freedom, three per floor.
    pub fn dofs(&self) -> usize {
        DOFS_PER_FLOOR * self.floors()
    }

    /// Number of damper coefficient groups (one uncertain coefficient each).
    pub fn damper_groups(&self) -> usize {
        self.dampers.iter().map(|d| d.placement.group + 1).max().unwrap_or(0)
    }

    /// Floor `floor`'s corners from its centre of mass (m), counter-clockwise from (+B/2, +D/2).
    pub fn corners(&self, floor: usize) -> [[f64; 2]; 4] {
        let centre = self.centres_of_mass[floor];
        self.plans[floor].corners().map(|[x, y]| [x - centre[0], y - centre[1]])
    }
}

/// The unit vector (cos β, sin β) of a direction β in degrees counter-clockwise from the plan's x
/// axis, exact along the axes: a damper along y must not see the x-sway through cos 90° ≈ 6·10⁻¹⁷,
/// which the power law |v|^α (α < 1) would lift to a force a millionth of its own.
pub fn plan_direction(degrees: f64) -> [f64; 2] {
    let quarter = degrees / 90.0;
    if quarter == quarter.round() {
        match (quarter.rem_euclid(4.0)) as u8 {
            0 => [1.0, 0.0],
            1 => [0.0, 1.0],
            2 => [-1.0, 0.0],
            _ => [0.0, -1.0],
        }
    } else {
        let (sin, cos) = degrees.to_radians().sin_cos();
        [cos, sin]
    }
}

/// A direction must be a finite unit vector.
fn check_direction(field: &str, direction: [f64; 2]) -> Result<()> {
    let length = direction[0].hypot(direction[1]);
    if !(length.is_finite() && (length - 1.0).abs() <= 1e-9) {
        return Err(Error::invalid(
            field,
            format!("must be a unit vector (cos β, sin β), got ({}, {})", direction[0], direction[1]),
        ));
    }
    Ok(())
}

fn per_floor(field: &str, entries: usize, floors: usize) -> Result<()> {
    if entries != floors {
        return Err(Error::invalid(field, format!("has {entries} entries but there are {floors} floors")));
    }
    Ok(())
}

#[cfg(test)]
mod tests;

/// The loads on a floor's (x, y, θ about its centre of mass) of a unit force along `direction` at
/// the plan's centre, which lies at −e from a centre of mass at e: the moment (−e) × F.
pub fn plan_arms(direction: [f64; 2], centre_of_mass: [f64; 2]) -> [f64; 3] {
    let [cos, sin] = direction;
    [cos, sin, centre_of_mass[1] * cos - centre_of_mass[0] * sin]
}
