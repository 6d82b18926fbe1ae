//! `frame40-3d`: the paper's 40-storey frame as the lateral system of a square building in both
//! directions. The plan is the frame's length on each side (four 6.1 m bays, 24.4 m); a copy of
//! the frame runs along each edge of the plan, two along x at y = ±12.2 m and two along y at
//! x = ±12.2 m, so that the perimeter frames also resist torsion; each carries the paper's damper
//! in its storeys. The paper's frame carries the floor's load over half the plan's depth (its wind
//! width, 12.2 m), so the building's floor mass is twice the frame's: each pair of parallel frames
//! then carries what the paper's frame does, and with its centre of mass at the plan's centre the
//! building sways along x (and along y) exactly as the plane frame under twice its load, and twists
//! at √3 times each sway frequency (the frames' lever arm B/2 against the floor's radius of
//! gyration B/√6).

use super::{DOFS_PER_FLOOR, Dof};
use super::{FloorPlan, PlanDamper, PlanarSystem, SpatialStructure, assemble, dof};
use crate::error::{Error, Result};
use crate::structure::frame40;
use faer::Mat;

/// The plan of every floor: 24.4 m × 24.4 m.
pub const FRAME40_3D_PLAN: FloorPlan = FloorPlan { breadth: 24.4, depth: 24.4 };

/// The building with every floor's centre of mass at `eccentricity` (m) from the plan's centre,
/// (0, 0) for the symmetric building; it must lie within a quarter of the plan of the centre.
pub fn frame40_3d(eccentricity: [f64; 2]) -> Result<SpatialStructure> {
    let quarter = 0.25 * FRAME40_3D_PLAN.breadth;
    if !eccentricity.iter().all(|e| e.is_finite() && e.abs() <= quarter) {
        return Err(Error::invalid(
            "eccentricity_m",
            format!(
                "({}, {}) m: each component must lie within ±{quarter} m (a quarter of the plan)",
                eccentricity[0], eccentricity[1]
            ),
        ));
    }
    let plane = frame40()?;
    let floors = plane.floors();
    let half = 0.5 * FRAME40_3D_PLAN.breadth;
    let centres = vec![eccentricity; floors];
    // (direction, the frame's line through this point)
    let (along_x, along_y) = ([1.0, 0.0], [0.0, 1.0]);
    let frames = [(along_x, [0.0, half]), (along_x, [0.0, -half]), (along_y, [half, 0.0]), (along_y, [-half, 0.0])];
    let systems: Vec<PlanarSystem> = frames
        .iter()
        .map(|&(direction, position)| PlanarSystem { stiffness: plane.stiffness.clone(), direction, position })
        .collect();
    let stiffness = assemble(&systems, &centres)?;
    let radius = FRAME40_3D_PLAN.radius_of_gyration();
    let mut mass = Mat::zeros(DOFS_PER_FLOOR * floors, DOFS_PER_FLOOR * floors);
    for j in 0..floors {
        let floor_mass = 2.0 * plane.mass[(j, j)];
        mass[(dof(j, Dof::X), dof(j, Dof::X))] = floor_mass;
        mass[(dof(j, Dof::Y), dof(j, Dof::Y))] = floor_mass;
        mass[(dof(j, Dof::Rotation), dof(j, Dof::Rotation))] = floor_mass * radius * radius;
    }
    let dampers = plane
        .dampers
        .iter()
        .flat_map(|d| {
            frames.iter().map(move |&(direction, position)| PlanDamper { placement: d.clone(), direction, position })
        })
        .collect();
    SpatialStructure::new(
        stiffness,
        mass,
        plane.floor_elevations.clone(),
        vec![FRAME40_3D_PLAN; floors],
        centres,
        plane.reference_youngs_modulus,
        dampers,
    )
}
