//! The three-dimensional reference models against the plane frame: `frame40-3d` with its centre
//! of mass at the plan's centre, driven along x by twice a plane storm's drag (its plan is twice
//! the frame's wind width), must move along x as the plane frame under that storm — its x
//! equations are the plane frame's times two, its y and twist equations are not excited — through
//! both integrators, the nonlinear dampers acting along their own directions.

use super::*;
use crate::progress::Silent;
use crate::structure::spatial::{Dof, SpatialModes, dof, frame40_3d};
use crate::structure::{Modes, frame40};
use crate::uncertainty::rng_from_seed;
use crate::wind::{FloorForces, StormGrid, WindLoads, WindSite};

const DAMPING_RATIO: f64 = 0.02;
/// The paper's exponent, and kN·s/m coefficients, where the dampers act.
const EXPONENT: f64 = 0.38;
const COEFFICIENTS: [f64; 4] = [5.0e4; 4];
const TIME_STEP: f64 = 0.01;

/// A 60 s storm at 35 m/s on the plane frame's floors.
fn plane_storm() -> FloorForces {
    let plane = frame40().unwrap();
    let loads = WindLoads::new(&WindSite::default(), &plane).unwrap();
    let storm = StormGrid { duration: 60.0, time_step: TIME_STEP };
    loads.floor_forces(35.0, &storm, &mut rng_from_seed(7)).unwrap()
}

/// The largest difference between two histories over the larger one's peak, and that peak.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let peak = a.iter().chain(b).fold(0.0, |m: f64, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0, |m: f64, (x, y)| m.max((x - y).abs())) / peak
}

/// The damper solve stops when no velocity moves by more than 10⁻⁹ of the largest, and the two
/// models reach that point along different iterations (120 against 40 unknowns, 160 dampers
/// against 40), so the histories agree to that tolerance carried through the storm, not to the
/// last bit: 10⁻⁷ of the peak, far below any difference a response would show.
const AGREEMENT: f64 = 1e-7;

#[test]
fn the_building_driven_along_x_sways_as_the_plane_frame_through_the_reduced_model() {
    let plane = frame40().unwrap();
    let building = frame40_3d([0.0, 0.0]).unwrap();
    let storm = plane_storm();
    let plane_modes = Modes::of(&plane, 3).unwrap();
    let plane_dampers = Dampers::new(&plane, &COEFFICIENTS, EXPONENT).unwrap();
    let plane_forces = storm.project(plane_modes.shapes.as_ref());
    let plane_run =
        integrate_reduced(&plane_modes, DAMPING_RATIO, &plane_dampers, &plane_forces, TIME_STEP, &Silent).unwrap();
    // Eight modes hold the plane frame's three in x (1, 4, 6) with their twins in y and two twists.
    let modes = SpatialModes::of(&building, 8).unwrap().modes();
    let dampers = Dampers::spatial(&building, &COEFFICIENTS, EXPONENT).unwrap();
    let forces = storm.scaled(2.0).on_plan([1.0, 0.0], &building.centres_of_mass).project(modes.shapes.as_ref());
    let run = integrate_reduced(&modes, DAMPING_RATIO, &dampers, &forces, TIME_STEP, &Silent).unwrap();
    let roof = |d: Dof| -> Vec<f64> {
        let row = dof(39, d);
        (0..run.displacements[0].len())
            .map(|t| (0..modes.count()).map(|m| modes.shapes[(row, m)] * run.displacements[m][t]).sum())
            .collect()
    };
    let plane_roof = plane_run.roof();
    let difference = relative_difference(&roof(Dof::X), &plane_roof);
    assert!(difference < AGREEMENT, "roof x differs from the plane frame's by {difference:e} of its peak");
    // The modes' shapes carry rounding (10⁻¹⁶) in the directions they do not move in, and the
    // law |v|^0.38 lifts velocities of that size to forces of (10⁻¹⁶)^0.38 ≈ 10⁻⁶ of the dampers'
    // own: y and twist stay at rest to a millionth of the sway, not to rounding.
    let peak = plane_roof.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    for d in [Dof::Y, Dof::Rotation] {
        let still = roof(d).iter().fold(0.0, |m: f64, v| m.max(v.abs()));
        assert!(still < 1e-6 * peak, "{d:?} moved by {still:e} (roof x peak {peak})");
    }
}

#[test]
fn the_building_driven_along_x_sways_as_the_plane_frame_through_the_full_model() {
    let plane = frame40().unwrap();
    let building = frame40_3d([0.0, 0.0]).unwrap();
    let storm = plane_storm();
    let plane_system = FullSystem::new(&plane, &Modes::all(&plane).unwrap(), 1.0, 1.0, DAMPING_RATIO);
    let plane_dampers = Dampers::new(&plane, &COEFFICIENTS, EXPONENT).unwrap();
    let plane_run = integrate_full(&plane_system, &plane_dampers, &storm, TIME_STEP, &Silent).unwrap();
    let all = SpatialModes::all(&building).unwrap().modes();
    let system = FullSystem::from_matrices(&building.mass, &building.stiffness, &all, 1.0, 1.0, DAMPING_RATIO);
    let dampers = Dampers::spatial(&building, &COEFFICIENTS, EXPONENT).unwrap();
    let run = integrate_full(
        &system,
        &dampers,
        &storm.scaled(2.0).on_plan([1.0, 0.0], &building.centres_of_mass),
        TIME_STEP,
        &Silent,
    )
    .unwrap();
    for floor in [19, 39] {
        let x = &run.displacements[dof(floor, Dof::X)];
        let difference = relative_difference(x, &plane_run.displacements[floor]);
        assert!(difference < AGREEMENT, "floor {} x differs by {difference:e} of its peak", floor + 1);
        let accelerations =
            relative_difference(&run.accelerations[dof(floor, Dof::X)], &plane_run.accelerations[floor]);
        assert!(accelerations < AGREEMENT, "floor {} acceleration differs by {accelerations:e}", floor + 1);
    }
    let peak = plane_run.displacements[39].iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    let still = [Dof::Y, Dof::Rotation]
        .iter()
        .map(|&d| run.displacements[dof(39, d)].iter().fold(0.0, |m: f64, v| m.max(v.abs())))
        .fold(0.0, f64::max);
    assert!(still < 1e-9 * peak, "y or twist moved by {still:e} (roof x peak {peak})");
}

/// With the centre of mass moved along y, the same drag along x twists the building: a damper's
/// lever arm now differs between the two x-frames, and the twist is what the eccentric modes say.
#[test]
fn an_eccentric_building_twists_under_drag_along_x() {
    let building = frame40_3d([0.0, 2.44]).unwrap();
    let storm = plane_storm();
    let modes = SpatialModes::of(&building, 8).unwrap().modes();
    let dampers = Dampers::spatial(&building, &COEFFICIENTS, EXPONENT).unwrap();
    let forces = storm.scaled(2.0).on_plan([1.0, 0.0], &building.centres_of_mass);
    // The drag acts at the plan's centre, 2.44 m below the centre of mass in y: its moment about
    // the centre of mass is 2.44 m times the force, on every floor.
    for (j, mean) in storm.mean.iter().enumerate() {
        let moment = forces.mean[dof(j, Dof::Rotation)];
        assert!((moment - 2.44 * 2.0 * mean).abs() <= 1e-12 * moment.abs(), "floor {}: {moment}", j + 1);
    }
    let run =
        integrate_reduced(&modes, DAMPING_RATIO, &dampers, &forces.project(modes.shapes.as_ref()), TIME_STEP, &Silent)
            .unwrap();
    let twist_peak = (0..run.displacements[0].len())
        .map(|t| {
            (0..modes.count()).map(|m| modes.shapes[(dof(39, Dof::Rotation), m)] * run.displacements[m][t]).sum::<f64>()
        })
        .fold(0.0, |m: f64, v| m.max(v.abs()));
    assert!(twist_peak > 1e-6, "the roof should twist, peak {twist_peak} rad");
}
