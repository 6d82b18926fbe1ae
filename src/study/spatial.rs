//! A study of a three-dimensional building: its structure and retained modes, the paper's uncertain
//! inputs with the wind's direction among them, the wind from that direction (drag, across-wind
//! force and torque), and one storm through its reference models, with its responses per direction
//! and at the corners of every floor.

use super::inputs::{PhysicalParameters, WIND_DIRECTION, frame_inputs, physical_parameters};
use super::{Order, StudySpec, check_admissible};
use crate::dynamics::{Dampers, FullSystem, ModalMotion, SampleModel, integrate_full, integrate_reduced};
use crate::error::{Error, Result};
use crate::progress::Silent;
use crate::structure::Modes;
use crate::structure::spatial::{
    CornerAcceleration, Dof, SpatialModes, SpatialStructure, corner_acceleration, dof, frame40_3d,
};
use crate::uncertainty::{Input, InputModel, Marginal, Rng};
use crate::wind::aerodynamic::Aerodynamics;
use crate::wind::{DirectionalWind, StormGrid, WindLoads};

/// Modes a three-dimensional study retains unless told: for `frame40-3d`, the plane frame's three
/// in x and in y and the two twists below its third (√3 times its first two), everything up to
/// 7.1 rad/s. A count that splits a pair of equal frequencies would sway the building along one axis
/// with a mode it lacks along the other.
pub const SPATIAL_MODES: usize = 8;

/// A study of a three-dimensional building.
#[derive(Debug, Clone)]
pub struct SpatialStudy {
    /// The preset's name.
    pub name: String,
    /// The building at the reference Young's modulus.
    pub structure: SpatialStructure,
    /// The retained modes at the reference stiffness and unit mass factor, with their shares.
    pub modes: SpatialModes,
    /// The uncertain inputs, by name: the paper's and the wind's direction.
    pub inputs: InputModel,
    /// The wind on this building at the site.
    pub wind: DirectionalWind,
    /// Exponent α of the damper law.
    pub damper_exponent: f64,
    /// Duration and time step of every storm.
    pub storm: StormGrid,
    /// Every mode, for the full-order model's classical damping (solved once, not per storm).
    all_modes: Modes,
}

impl SpatialStudy {
    /// The study of a three-dimensional preset (`frame40-3d`) with its centre of mass at
    /// `eccentricity` from the plan's centre, the wake loads of `aerodynamics`, and the spec's
    /// inputs, site, damper exponent, modes and storm.
    pub fn preset(spec: &StudySpec, eccentricity: [f64; 2], aerodynamics: Aerodynamics) -> Result<Self> {
        let name = match spec.preset.as_deref() {
            Some("frame40-3d") => "frame40-3d",
            other => {
                return Err(Error::invalid(
                    "preset",
                    format!(
                        "`{}` is not a three-dimensional preset; the one there is: frame40-3d",
                        other.unwrap_or("")
                    ),
                ));
            }
        };
        if spec.structure.is_some() {
            return Err(Error::invalid(
                "structure",
                "a custom structure of a three-dimensional study is not read yet; use the preset",
            ));
        }
        let structure = frame40_3d(eccentricity)?;
        let modes = SpatialModes::of(&structure, spec.modes.unwrap_or(SPATIAL_MODES))?;
        // The dampers act in kN·s/m, as in frame40-kn.
        let mut inputs = frame_inputs(structure.reference_youngs_modulus, structure.damper_groups(), 1000.0);
        inputs
            .inputs
            .push(Input { name: WIND_DIRECTION.into(), marginal: Marginal::Uniform { lower: 0.0, upper: 360.0 } });
        for (input, marginal) in &spec.inputs {
            inputs = inputs.with_marginal(input, *marginal)?;
        }
        for input in &inputs.inputs {
            check_admissible(input)?;
        }
        let site = spec.wind.clone().unwrap_or_default();
        let wind = DirectionalWind::new(&site, &structure, Some(aerodynamics))?;
        let storm = StormGrid::new(spec.duration_s.unwrap_or(900.0), spec.time_step_s.unwrap_or(0.01), &site)?;
        let damper_exponent = spec.damper_exponent.unwrap_or(0.38);
        Dampers::spatial(&structure, &vec![0.0; structure.damper_groups()], damper_exponent)?;
        let all_modes = SpatialModes::all(&structure)?.modes();
        Ok(SpatialStudy { name: name.into(), structure, modes, inputs, wind, damper_exponent, storm, all_modes })
    }

    /// A sample's physical parameters and its wind direction (degrees).
    pub fn parameters(&self, x: &[f64]) -> Result<(PhysicalParameters, f64)> {
        let parameters = physical_parameters(&self.inputs, self.structure.damper_groups(), x)?;
        Ok((parameters, x[self.inputs.index_of(WIND_DIRECTION)?]))
    }

    /// One storm at the sample `x` through the reduced (retained modes) or the full (every degree
    /// of freedom) reference model.
    pub fn reference_run(&self, x: &[f64], order: Order, rng: &mut Rng) -> Result<SpatialRun> {
        let (p, direction) = self.parameters(x)?;
        WindLoads::check_speed(p.wind_speed)?;
        let stiffness = p.youngs_modulus / self.structure.reference_youngs_modulus;
        let dampers = Dampers::spatial(&self.structure, &p.damper_coefficients, self.damper_exponent)?;
        let dt = self.storm.time_step;
        let forces = self.wind.floor_forces(p.wind_speed, direction, &self.storm, rng)?;
        match order {
            Order::Reduced => {
                let modes = self.modes.modes().scaled(stiffness, p.mass_factor);
                let modal_forces = forces.project(modes.shapes.as_ref());
                let response = integrate_reduced(&modes, p.damping_ratio, &dampers, &modal_forces, dt, &Silent)?;
                let motion: ModalMotion = response.motion();
                let accelerations =
                    SampleModel::new(&modes, p.damping_ratio, &dampers).modal_accelerations(&motion, &modal_forces);
                Ok(SpatialRun {
                    displacements: on_floors(&modes, &motion.displacements),
                    accelerations: on_floors(&modes, &accelerations),
                    direction,
                })
            }
            Order::Full => {
                let system = FullSystem::from_matrices(
                    &self.structure.mass,
                    &self.structure.stiffness,
                    &self.all_modes,
                    stiffness,
                    p.mass_factor,
                    p.damping_ratio,
                );
                let response = integrate_full(&system, &dampers, &forces, dt, &Silent)?;
                Ok(SpatialRun {
                    displacements: response.displacements,
                    accelerations: response.accelerations,
                    direction,
                })
            }
        }
    }
}

/// Φ·q(t) over every degree of freedom.
fn on_floors(modes: &Modes, modal: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let steps = modal.first().map_or(0, Vec::len);
    (0..modes.shapes.nrows())
        .map(|i| {
            let mut series = vec![0.0; steps];
            for (m, q) in modal.iter().enumerate() {
                let phi = modes.shapes[(i, m)];
                if phi != 0.0 {
                    series.iter_mut().zip(q).for_each(|(s, v)| *s += phi * v);
                }
            }
            series
        })
        .collect()
}

/// One storm's motion of a three-dimensional building: every degree of freedom's displacement
/// (m, rad) and acceleration (m/s², rad/s², relative to the ground), as [`dof`] numbers them.
#[derive(Debug, Clone)]
pub struct SpatialRun {
    /// `[dof][step]`.
    pub displacements: Vec<Vec<f64>>,
    /// `[dof][step]`.
    pub accelerations: Vec<Vec<f64>>,
    /// The storm's wind direction (degrees).
    pub direction: f64,
}

/// A floor's peak responses in one storm.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorPeaks {
    /// Peak |u_x|, |u_y| (m) and |θ| (rad) at the centre of mass.
    pub displacement: [f64; 3],
    /// Peak inter-storey drift ratio along x and y at the centre of mass (relative displacement over
    /// the storey's height).
    pub drift: [f64; 2],
    /// Peak |ü_x|, |ü_y| (m/s²) and |θ̈| (rad/s²) at the centre of mass.
    pub acceleration: [f64; 3],
    /// The resultant horizontal acceleration at the floor's worst corner, peak and RMS.
    pub corner: CornerAcceleration,
}

impl SpatialRun {
    /// Every floor's peaks, from the ground up.
    pub fn floor_peaks(&self, structure: &SpatialStructure) -> Vec<FloorPeaks> {
        let peak = |series: &[f64]| series.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut below = 0.0;
        (0..structure.floors())
            .map(|j| {
                let storey = structure.floor_elevations[j] - below;
                below = structure.floor_elevations[j];
                let displacement = [Dof::X, Dof::Y, Dof::Rotation].map(|d| peak(&self.displacements[dof(j, d)]));
                let drift = [Dof::X, Dof::Y].map(|d| {
                    let upper = &self.displacements[dof(j, d)];
                    match j {
                        0 => peak(upper) / storey,
                        _ => {
                            let lower = &self.displacements[dof(j - 1, d)];
                            upper.iter().zip(lower).fold(0.0f64, |m, (u, l)| m.max((u - l).abs())) / storey
                        }
                    }
                });
                let acceleration = [Dof::X, Dof::Y, Dof::Rotation].map(|d| peak(&self.accelerations[dof(j, d)]));
                let corner = corner_acceleration(
                    &structure.plans[j],
                    structure.centres_of_mass[j],
                    &self.accelerations[dof(j, Dof::X)],
                    &self.accelerations[dof(j, Dof::Y)],
                    &self.accelerations[dof(j, Dof::Rotation)],
                );
                FloorPeaks { displacement, drift, acceleration, corner }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(inputs: &[(&str, Marginal)]) -> StudySpec {
        let mut spec = StudySpec { preset: Some("frame40-3d".into()), ..Default::default() };
        for (name, marginal) in inputs {
            spec.inputs.insert(name.to_string(), *marginal);
        }
        spec
    }

    #[test]
    fn the_direction_is_an_input_that_may_take_any_angle() {
        let study = SpatialStudy::preset(&spec(&[]), [0.0, 0.0], Aerodynamics::Published).unwrap();
        let names: Vec<&str> = study.inputs.names().collect();
        assert_eq!(names.last(), Some(&WIND_DIRECTION));
        assert_eq!(study.modes.count(), SPATIAL_MODES);
        let westerly = spec(&[(WIND_DIRECTION, Marginal::Normal { mean: -20.0, sd: 30.0 })]);
        assert!(SpatialStudy::preset(&westerly, [0.0, 0.0], Aerodynamics::Published).is_ok());
        let slow = spec(&[("wind_speed", Marginal::Normal { mean: 30.0, sd: 10.0 })]);
        let refused = SpatialStudy::preset(&slow, [0.0, 0.0], Aerodynamics::Published).unwrap_err().to_string();
        assert!(refused.contains("inputs.wind_speed"), "{refused}");
        let plane = StudySpec { preset: Some("frame40-kn".into()), ..Default::default() };
        let refused = SpatialStudy::preset(&plane, [0.0, 0.0], Aerodynamics::Published).unwrap_err().to_string();
        assert!(refused.contains("preset"), "{refused}");
    }

    /// Drifts are relative motions over the storey's height, and on a plan whose centre of mass is
    /// its centre the corners see at least the centre's sway (their mean square over the four is
    /// the centre's plus the twist's): one short storm's peaks, floor by floor.
    #[test]
    fn a_storms_floor_peaks_hold_together() {
        let mut spec = spec(&[]);
        spec.duration_s = Some(60.0);
        spec.modes = Some(5);
        let mut study = SpatialStudy::preset(&spec, [0.0, 0.0], Aerodynamics::Published).unwrap();
        study.inputs = study.inputs.with_fixed(WIND_DIRECTION, 30.0).unwrap();
        let x = study.inputs.means();
        let run = study.reference_run(&x, Order::Reduced, &mut crate::uncertainty::rng_from_seed(3)).unwrap();
        assert_eq!(run.direction, 30.0);
        let peaks = run.floor_peaks(&study.structure);
        assert_eq!(peaks.len(), 40);
        let first = &peaks[0];
        let storey = study.structure.floor_elevations[0];
        assert!((first.drift[0] - first.displacement[0] / storey).abs() < 1e-15);
        for p in &peaks {
            let centre = p.acceleration[0].max(p.acceleration[1]);
            assert!(p.corner.peak >= centre * (1.0 - 1e-12), "{p:?}");
            assert!(p.corner.rms <= p.corner.peak && p.corner.rms > 0.0, "{p:?}");
        }
        // The wake's torque twists it.
        assert!(peaks[39].displacement[2] > 0.0);
    }
}
