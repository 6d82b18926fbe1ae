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
    CornerAcceleration, CustomSpatialStructure, Dof, SpatialModes, SpatialStructure, corner_acceleration, dof,
    frame40_3d,
};
use crate::uncertainty::{Input, InputModel, Marginal, Rng};
use crate::wind::aerodynamic::Aerodynamics;
use crate::wind::{DirectionalWind, StormGrid, WindLoads, rms_stride};
use std::borrow::Cow;

/// Modes a three-dimensional study retains unless told: for `frame40-3d`, the plane frame's three
/// in x and in y and the two twists below its third (√3 times its first two), everything up to
/// 7.1 rad/s. A count that splits a pair of equal frequencies would sway the building along one axis
/// with a mode it lacks along the other.
pub const SPATIAL_MODES: usize = 8;

/// The inputs that move every floor's centre of mass from where the structure puts it (m, along
/// the plan's x and y): the accidental eccentricity the codes ask for, or an uncertain
/// distribution of the floors' contents. Held at 0 unless the spec says otherwise.
pub const ECCENTRICITY_INPUTS: [&str; 2] = ["eccentricity_x", "eccentricity_y"];

/// Probability of an eccentricity beyond its limit that is no objection (as for the other inputs'
/// supports).
const NEGLIGIBLE_PROBABILITY: f64 = 1e-12;

/// A study of a three-dimensional building.
#[derive(Debug, Clone)]
pub struct SpatialStudy {
    /// The preset's name.
    pub name: String,
    /// The building at the reference Young's modulus, its centres of mass at the eccentricity
    /// inputs' means.
    pub structure: SpatialStructure,
    /// The retained modes of `structure` at the reference stiffness and unit mass factor, with
    /// their shares.
    pub modes: SpatialModes,
    /// The uncertain inputs, by name: the paper's, the wind's direction and the eccentricity.
    pub inputs: InputModel,
    /// The wind on this building at the site.
    pub wind: DirectionalWind,
    /// Exponent α of the damper law.
    pub damper_exponent: f64,
    /// Duration and time step of every storm.
    pub storm: StormGrid,
    /// How many modes a sample's reduced model retains.
    mode_count: usize,
    /// Where the building comes from, to rebuild it at a sample's eccentricity.
    building: Building,
    /// The eccentricity `structure` is built at.
    eccentricity: [f64; 2],
    /// Every mode of `structure`, for the full-order model's classical damping (solved once, not
    /// per storm).
    all_modes: Modes,
}

/// A sample of a three-dimensional study's inputs, as physical values.
#[derive(Debug, Clone, PartialEq)]
pub struct SpatialParameters {
    /// The paper's inputs.
    pub physical: PhysicalParameters,
    /// Where the wind blows towards (degrees counter-clockwise from the plan's x axis).
    pub direction: f64,
    /// How far every floor's centre of mass lies from where the structure puts it (m).
    pub eccentricity: [f64; 2],
}

/// A sample's building: the study's own when its eccentricity is the study's, else rebuilt.
struct SampleBuilding<'a> {
    structure: Cow<'a, SpatialStructure>,
    modes: Cow<'a, SpatialModes>,
    all_modes: Option<Cow<'a, Modes>>,
}

impl SpatialStudy {
    /// The study of a three-dimensional preset (`frame40-3d`) or of the spec's custom
    /// `spatial_structure`, with the wake loads of `aerodynamics`, and the spec's inputs, site,
    /// damper exponent, modes and storm.
    pub fn from_spec(spec: &StudySpec, aerodynamics: Aerodynamics) -> Result<Self> {
        if spec.structure.is_some() {
            return Err(Error::invalid(
                "structure",
                "is a plane frame's; a three-dimensional building is given as `spatial_structure`",
            ));
        }
        let (name, building) = match (spec.preset.as_deref(), &spec.spatial_structure) {
            (None, Some(custom)) => ("custom", Building::Custom(custom.clone())),
            (Some("frame40-3d"), None) => ("frame40-3d", Building::Frame40),
            (Some(_), Some(_)) => {
                return Err(Error::invalid(
                    "preset",
                    "give a three-dimensional preset or a `spatial_structure`, not both",
                ));
            }
            (other, None) => {
                return Err(Error::invalid(
                    "preset",
                    format!(
                        "`{}` is not a three-dimensional preset; the one there is: frame40-3d",
                        other.unwrap_or("")
                    ),
                ));
            }
        };
        // The preset's dampers act in kN·s/m, as in frame40-kn; a custom building's in N·s/m.
        let reference = building.at([0.0, 0.0])?;
        let damper_scale = if matches!(building, Building::Frame40) { 1000.0 } else { 1.0 };
        let mut inputs = frame_inputs(reference.reference_youngs_modulus, reference.damper_groups(), damper_scale);
        inputs
            .inputs
            .push(Input { name: WIND_DIRECTION.into(), marginal: Marginal::Uniform { lower: 0.0, upper: 360.0 } });
        for name in ECCENTRICITY_INPUTS {
            inputs.inputs.push(Input { name: name.into(), marginal: Marginal::Constant { value: 0.0 } });
        }
        for (input, marginal) in &spec.inputs {
            inputs = inputs.with_marginal(input, *marginal)?;
        }
        for input in &inputs.inputs {
            if !ECCENTRICITY_INPUTS.contains(&input.name.as_str()) {
                check_admissible(input)?;
            }
        }
        let limit = building.eccentricity_limit(&reference);
        for name in ECCENTRICITY_INPUTS {
            let marginal = inputs.marginal(name)?;
            if building.fixes_centres() && *marginal != (Marginal::Constant { value: 0.0 }) {
                return Err(Error::invalid(
                    format!("inputs.{name}"),
                    "a building given by its matrices holds its centres of mass in them; give it by `storeys` to \
                     move them",
                ));
            }
            check_eccentricity(name, marginal, limit)?;
        }
        let mean_eccentricity =
            [inputs.marginal(ECCENTRICITY_INPUTS[0])?.mean(), inputs.marginal(ECCENTRICITY_INPUTS[1])?.mean()];
        let structure = building.at(mean_eccentricity)?;
        let mode_count = spec.modes.unwrap_or(SPATIAL_MODES);
        let modes = SpatialModes::of(&structure, mode_count)?;
        let site = spec.wind.clone().unwrap_or_default();
        let wind = DirectionalWind::new(&site, &structure, Some(aerodynamics))?;
        let storm = StormGrid::new(spec.duration_s.unwrap_or(900.0), spec.time_step_s.unwrap_or(0.01), &site)?;
        let damper_exponent = spec.damper_exponent.unwrap_or(0.38);
        Dampers::check_exponent(damper_exponent)?;
        let all_modes = SpatialModes::all(&structure)?.modes();
        Ok(SpatialStudy {
            name: name.into(),
            structure,
            modes,
            inputs,
            wind,
            damper_exponent,
            storm,
            mode_count,
            building,
            eccentricity: mean_eccentricity,
            all_modes,
        })
    }

    /// A sample's physical parameters, wind direction and eccentricity.
    pub fn parameters(&self, x: &[f64]) -> Result<SpatialParameters> {
        let physical = physical_parameters(&self.inputs, self.structure.damper_groups(), x)?;
        let value = |name: &str| -> Result<f64> { Ok(x[self.inputs.index_of(name)?]) };
        Ok(SpatialParameters {
            physical,
            direction: value(WIND_DIRECTION)?,
            eccentricity: [value(ECCENTRICITY_INPUTS[0])?, value(ECCENTRICITY_INPUTS[1])?],
        })
    }

    /// The building of a sample whose centres of mass lie at `eccentricity`: the study's own, or
    /// rebuilt with its modes (and every mode, for a full-order run).
    fn sample_building(&self, eccentricity: [f64; 2], order: Order) -> Result<SampleBuilding<'_>> {
        if eccentricity == self.eccentricity {
            return Ok(SampleBuilding {
                structure: Cow::Borrowed(&self.structure),
                modes: Cow::Borrowed(&self.modes),
                all_modes: Some(Cow::Borrowed(&self.all_modes)),
            });
        }
        let structure = self.building.at(eccentricity)?;
        let modes = SpatialModes::of(&structure, self.mode_count)?;
        let all_modes = match order {
            Order::Full => Some(Cow::Owned(SpatialModes::all(&structure)?.modes())),
            Order::Reduced => None,
        };
        Ok(SampleBuilding { structure: Cow::Owned(structure), modes: Cow::Owned(modes), all_modes })
    }

    /// One storm at the sample `x` through the reduced (retained modes) or the full (every degree
    /// of freedom) reference model.
    pub fn reference_run(&self, x: &[f64], order: Order, rng: &mut Rng) -> Result<SpatialRun> {
        let sample = self.parameters(x)?;
        let p = &sample.physical;
        WindLoads::check_speed(p.wind_speed)?;
        let building = self.sample_building(sample.eccentricity, order)?;
        let structure = building.structure.as_ref();
        let stiffness = p.youngs_modulus / structure.reference_youngs_modulus;
        let dampers = Dampers::spatial(structure, &p.damper_coefficients, self.damper_exponent)?;
        let dt = self.storm.time_step;
        let forces =
            self.wind.floor_forces(p.wind_speed, sample.direction, &structure.centres_of_mass, &self.storm, rng)?;
        let direction = sample.direction;
        let centres_of_mass = structure.centres_of_mass.clone();
        match order {
            Order::Reduced => {
                let modes = building.modes.modes().scaled(stiffness, p.mass_factor);
                let modal_forces = forces.project(modes.shapes.as_ref());
                let response = integrate_reduced(&modes, p.damping_ratio, &dampers, &modal_forces, dt, &Silent)?;
                let motion: ModalMotion = response.motion();
                let accelerations =
                    SampleModel::new(&modes, p.damping_ratio, &dampers).modal_accelerations(&motion, &modal_forces);
                Ok(SpatialRun {
                    displacements: on_floors(&modes, &motion.displacements),
                    accelerations: on_floors(&modes, &accelerations),
                    direction,
                    centres_of_mass,
                })
            }
            Order::Full => {
                let all_modes = building
                    .all_modes
                    .as_deref()
                    .ok_or_else(|| Error::Internal("a full-order sample building without its modes".into()))?;
                let system = FullSystem::from_matrices(
                    &structure.mass,
                    &structure.stiffness,
                    all_modes,
                    stiffness,
                    p.mass_factor,
                    p.damping_ratio,
                );
                let response = integrate_full(&system, &dampers, &forces, dt, &Silent)?;
                Ok(SpatialRun {
                    displacements: response.displacements,
                    accelerations: response.accelerations,
                    direction,
                    centres_of_mass,
                })
            }
        }
    }
}

/// Where a study's building comes from: a sample's eccentricity rebuilds it.
#[derive(Debug, Clone)]
enum Building {
    /// `frame40-3d`.
    Frame40,
    /// The spec's `spatial_structure`.
    Custom(CustomSpatialStructure),
}

impl Building {
    /// The building with every floor's centre of mass moved by `eccentricity` (m) from where it
    /// puts it.
    fn at(&self, eccentricity: [f64; 2]) -> Result<SpatialStructure> {
        match self {
            Building::Frame40 => frame40_3d(eccentricity),
            Building::Custom(custom) if eccentricity == [0.0, 0.0] => custom.build(),
            Building::Custom(custom) => {
                let mut moved = custom.clone();
                let Some(storeys) = moved.storeys.as_mut() else {
                    return Err(Error::Internal("an eccentricity for a building given by its matrices".into()));
                };
                for storey in storeys {
                    let [x, y] = storey.centre_of_mass_m;
                    storey.centre_of_mass_m = [x + eccentricity[0], y + eccentricity[1]];
                }
                moved.build()
            }
        }
    }

    /// Whether the building's centres of mass are fixed by its matrices (no eccentricity moves them).
    fn fixes_centres(&self) -> bool {
        matches!(self, Building::Custom(custom) if custom.storeys.is_none())
    }

    /// How far the eccentricity may move the centres of mass (m): a quarter of the smallest plan's
    /// smaller side less the farthest a floor's own centre already lies from its plan's centre.
    fn eccentricity_limit(&self, reference: &SpatialStructure) -> f64 {
        let quarter = reference.plans.iter().map(|p| 0.25 * p.breadth.min(p.depth)).fold(f64::INFINITY, f64::min);
        let own = reference.centres_of_mass.iter().map(|c| c[0].abs().max(c[1].abs())).fold(0.0, f64::max);
        (quarter - own).max(0.0)
    }
}

/// Refuses an eccentricity whose distribution reaches beyond ±`limit` (m) with more than a
/// negligible probability: the building's centres of mass must stay on their plans.
fn check_eccentricity(name: &str, marginal: &Marginal, limit: f64) -> Result<()> {
    let beyond = marginal.cdf(-limit) + marginal.survival(limit);
    if beyond > NEGLIGIBLE_PROBABILITY {
        let (lower, upper) = marginal.support();
        return Err(Error::invalid(
            format!("inputs.{name}"),
            format!(
                "must stay within ±{limit} m (a quarter of the plan), but reaches [{lower}, {upper}] m with \
                 probability {beyond:.1e} outside; choose a uniform law or a normal of a smaller deviation"
            ),
        ));
    }
    Ok(())
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
    /// Each floor's centre of mass in this storm, from its plan's centre (m): where the corners
    /// are measured from.
    pub centres_of_mass: Vec<[f64; 2]>,
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
    /// Every floor's peaks, from the ground up, of a storm of steps of `time_step` (s) (the RMS
    /// samples it as a floor's RMS acceleration does, [`rms_stride`]).
    pub fn floor_peaks(&self, structure: &SpatialStructure, time_step: f64) -> Vec<FloorPeaks> {
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
                    self.centres_of_mass[j],
                    &self.accelerations[dof(j, Dof::X)],
                    &self.accelerations[dof(j, Dof::Y)],
                    &self.accelerations[dof(j, Dof::Rotation)],
                    rms_stride(time_step),
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
        let study = SpatialStudy::from_spec(&spec(&[]), Aerodynamics::Published).unwrap();
        let names: Vec<&str> = study.inputs.names().collect();
        assert_eq!(names[names.len() - 3..], [WIND_DIRECTION, ECCENTRICITY_INPUTS[0], ECCENTRICITY_INPUTS[1]]);
        assert_eq!(study.modes.count(), SPATIAL_MODES);
        let westerly = spec(&[(WIND_DIRECTION, Marginal::Normal { mean: -20.0, sd: 30.0 })]);
        assert!(SpatialStudy::from_spec(&westerly, Aerodynamics::Published).is_ok());
        let slow = spec(&[("wind_speed", Marginal::Normal { mean: 30.0, sd: 10.0 })]);
        let refused = SpatialStudy::from_spec(&slow, Aerodynamics::Published).unwrap_err().to_string();
        assert!(refused.contains("inputs.wind_speed"), "{refused}");
        let plane = StudySpec { preset: Some("frame40-kn".into()), ..Default::default() };
        let refused = SpatialStudy::from_spec(&plane, Aerodynamics::Published).unwrap_err().to_string();
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
        let mut study = SpatialStudy::from_spec(&spec, Aerodynamics::Published).unwrap();
        study.inputs = study.inputs.with_fixed(WIND_DIRECTION, 30.0).unwrap();
        let x = study.inputs.means();
        let run = study.reference_run(&x, Order::Reduced, &mut crate::uncertainty::rng_from_seed(3)).unwrap();
        assert_eq!(run.direction, 30.0);
        let peaks = run.floor_peaks(&study.structure, study.storm.time_step);
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

    /// An uncertain eccentricity moves each sample's centres of mass (and the corners are measured
    /// from them); a law that reaches beyond a quarter of the plan is refused by its input's name.
    #[test]
    fn an_uncertain_eccentricity_moves_each_samples_centres_of_mass() {
        let eccentric = spec(&[(ECCENTRICITY_INPUTS[1], Marginal::Uniform { lower: -1.0, upper: 1.0 })]);
        let mut short = eccentric.clone();
        short.duration_s = Some(20.0);
        short.modes = Some(5);
        let study = SpatialStudy::from_spec(&short, Aerodynamics::Published).unwrap();
        assert_eq!(study.structure.centres_of_mass[0], [0.0, 0.0]);
        let mut x = study.inputs.means();
        x[study.inputs.index_of(ECCENTRICITY_INPUTS[1]).unwrap()] = 0.8;
        x[study.inputs.index_of(WIND_DIRECTION).unwrap()] = 0.0;
        let run = study.reference_run(&x, Order::Reduced, &mut crate::uncertainty::rng_from_seed(5)).unwrap();
        assert!(run.centres_of_mass.iter().all(|c| *c == [0.0, 0.8]));
        assert_eq!(study.parameters(&x).unwrap().eccentricity, [0.0, 0.8]);
        let wide = spec(&[(ECCENTRICITY_INPUTS[0], Marginal::Normal { mean: 0.0, sd: 3.0 })]);
        let refused = SpatialStudy::from_spec(&wide, Aerodynamics::Published).unwrap_err().to_string();
        assert!(refused.contains("inputs.eccentricity_x"), "{refused}");
    }
}
