//! One study: a structure, its uncertain inputs by name, the wind site, the damper law and the storm
//! grid (here, built from a [`StudySpec`] and checked), its storms and reference runs (`storms`).
//! The paper's case study comes as two presets (`presets`), with its input model (`inputs`).
//!
//! The input names are the same on the command line, in files and over HTTP: `youngs_modulus` (Pa),
//! `mass_factor`, `damping_ratio` (shared by all modes), `damper_c1` … `damper_cG` (N·(s/m)^α, one
//! per damper group from the ground up) and `wind_speed` (m/s at the station, 10 m); a
//! three-dimensional study (`spatial`) adds `wind_direction` (degrees).

mod inputs;
mod presets;
mod spatial;
mod spec;
mod storms;

pub use inputs::{PhysicalParameters, WIND_DIRECTION, WIND_SPEED};
pub use presets::{DEFAULT_PRESET, PRESETS, SPATIAL_PRESETS};
pub use spatial::{ECCENTRICITY_INPUTS, FloorPeaks, SPATIAL_MODES, SpatialParameters, SpatialRun, SpatialStudy};
pub use spec::StudySpec;
pub use storms::{Order, StormRun, WindPath};

use crate::dynamics::{Dampers, FullSystem};
use crate::error::{Error, Result};
use crate::structure::{Modes, Structure};
use crate::uncertainty::InputModel;
use crate::wind::{ModalWind, StormGrid, WindLoads};
use inputs::{check_admissible, default_inputs, physical_parameters};

/// A validated study.
#[derive(Debug, Clone)]
pub struct Study {
    /// The preset's name, `custom`, or the preset's name with `+custom` when a custom structure
    /// replaces its own.
    pub name: String,
    /// The spec it was built from (inputs and storm as given, before later changes).
    spec: StudySpec,
    /// The building at the reference Young's modulus.
    pub structure: Structure,
    /// The retained modes at the reference stiffness and unit mass factor.
    pub modes: Modes,
    /// All N modes, for the classical damping of the full-order model.
    pub all_modes: Modes,
    /// The uncertain inputs, by name.
    pub inputs: InputModel,
    /// The wind loads of the site on this structure.
    pub wind: WindLoads,
    /// The modal-force fast path for `modes`, its spectral table built once.
    pub modal_wind: ModalWind,
    /// Exponent α of the damper law.
    pub damper_exponent: f64,
    /// Duration and time step of every storm.
    pub storm: StormGrid,
}

/// Most modes a study retains: the modal wind costs the square of the modes per storm and the
/// coupled NARX dictionaries grow with them; the paper's building needs three.
pub const MAX_MODES: usize = 10;

impl Study {
    /// A preset study by name.
    pub fn preset(name: &str) -> Result<Study> {
        Study::from_spec(&StudySpec { preset: Some(name.to_string()), ..Default::default() })
    }

    /// Builds and checks the study a spec describes, with the paper's values where it says nothing.
    pub fn from_spec(spec: &StudySpec) -> Result<Study> {
        let (name, structure, damper_scale) = presets::resolve(spec)?;
        let mut inputs = default_inputs(&structure, damper_scale);
        for (input, marginal) in &spec.inputs {
            inputs = inputs.with_marginal(input, *marginal)?;
        }
        for input in &inputs.inputs {
            check_admissible(input)?;
        }
        let modes_count = spec.modes.unwrap_or(3);
        if modes_count > MAX_MODES {
            return Err(Error::invalid("modes", format!("must be at most {MAX_MODES}, got {modes_count}")));
        }
        let modes = Modes::of(&structure, modes_count)?;
        let all_modes = Modes::all(&structure)?;
        let site = spec.wind.clone().unwrap_or_default();
        let wind = WindLoads::new(&site, &structure)?;
        let modal_wind = ModalWind::new(&wind, modes.shapes.as_ref());
        let damper_exponent = spec.damper_exponent.unwrap_or(0.38);
        if !(damper_exponent.is_finite() && damper_exponent > 0.0 && damper_exponent <= 2.0) {
            return Err(Error::invalid("damper_exponent", format!("must lie in (0, 2], got {damper_exponent}")));
        }
        let storm = StormGrid::new(spec.duration_s.unwrap_or(900.0), spec.time_step_s.unwrap_or(0.01), &site)?;
        // The modal forces are simulated as a process of as many components as modes, whose period
        // 2πn/Δω is the shortest of any path: a longer storm would repeat itself.
        let period = wind.grid().period(modes_count);
        if storm.duration > period {
            return Err(Error::invalid(
                "duration_s",
                format!(
                    "{} s is longer than the period of the simulated wind ({period:.0} s); raise wind.frequencies",
                    storm.duration
                ),
            ));
        }
        Ok(Study {
            name,
            spec: spec.clone(),
            structure,
            modes,
            all_modes,
            inputs,
            wind,
            modal_wind,
            damper_exponent,
            storm,
        })
    }

    /// A spec that rebuilds exactly this study: every input's marginal and the storm grid as they
    /// are now.
    pub fn resolved_spec(&self) -> StudySpec {
        let mut spec = self.spec.clone();
        spec.inputs = self.inputs.inputs.iter().map(|i| (i.name.clone(), i.marginal)).collect();
        spec.duration_s = Some(self.storm.duration);
        spec.time_step_s = Some(self.storm.time_step);
        spec.modes = Some(self.modes.count());
        spec
    }

    /// The same study on another storm grid.
    pub fn with_storm(mut self, duration: f64, time_step: f64) -> Result<Study> {
        self.storm = StormGrid::new(duration, time_step, &self.wind.site)?;
        Ok(self)
    }

    /// Reads a sample (values in the input model's order) as physical parameters.
    pub fn parameters(&self, x: &[f64]) -> Result<PhysicalParameters> {
        physical_parameters(&self.inputs, self.structure.damper_groups(), x)
    }

    /// Stiffness factor κ = E / E_ref of a sample.
    pub fn stiffness_factor(&self, p: &PhysicalParameters) -> f64 {
        p.youngs_modulus / self.structure.reference_youngs_modulus
    }

    /// The full-order system of a sample: every mode, its stiffness, mass and damping ratio.
    pub fn full_system(&self, p: &PhysicalParameters) -> FullSystem {
        FullSystem::new(&self.structure, &self.all_modes, self.stiffness_factor(p), p.mass_factor, p.damping_ratio)
    }

    /// The retained modes of a sample: shapes fixed, ω ∝ √(κ/μ), M_m ∝ μ.
    pub fn sample_modes(&self, p: &PhysicalParameters) -> Modes {
        self.modes.scaled(self.stiffness_factor(p), p.mass_factor)
    }

    /// The dampers of a sample, with its coefficients.
    pub fn dampers(&self, p: &PhysicalParameters) -> Result<Dampers> {
        Dampers::new(&self.structure, &p.damper_coefficients, self.damper_exponent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::Marginal;

    /// A Gumbel law of annual maxima is a wind speed's marginal (10⁻⁴³ below 0 m/s); a normal law
    /// with a tenth of a percent below 0, or a uniform law from 0, is not.
    #[test]
    fn inputs_may_reach_below_zero_only_with_a_negligible_probability() {
        let with = |name: &str, marginal: Marginal| {
            let mut spec = StudySpec { preset: Some("frame40-kn".into()), ..Default::default() };
            spec.inputs.insert(name.into(), marginal);
            Study::from_spec(&spec)
        };
        assert!(with("wind_speed", Marginal::Gumbel { location: 22.0, scale: 2.2 }).is_ok());
        assert!(with("wind_speed", Marginal::Normal { mean: 30.0, sd: 3.5 }).is_ok());
        let refused = with("wind_speed", Marginal::Normal { mean: 30.0, sd: 10.0 }).unwrap_err().to_string();
        assert!(refused.contains("inputs.wind_speed") && refused.contains("1.3e-3"), "{refused}");
        assert!(with("wind_speed", Marginal::Uniform { lower: 0.0, upper: 40.0 }).is_err());
        assert!(with("damper_c1", Marginal::Uniform { lower: 0.0, upper: 40.0 }).is_ok());
        assert!(with("damper_c1", Marginal::Uniform { lower: -1.0, upper: 40.0 }).is_err());
    }

    #[test]
    fn presets_have_the_papers_eight_inputs() {
        let p = Study::preset("frame40-kn").unwrap();
        let names: Vec<&str> = p.inputs.names().collect();
        assert_eq!(
            names,
            [
                "youngs_modulus",
                "mass_factor",
                "damping_ratio",
                "damper_c1",
                "damper_c2",
                "damper_c3",
                "damper_c4",
                "wind_speed"
            ]
        );
        assert_eq!(p.inputs.marginal("damper_c3").unwrap(), &Marginal::Uniform { lower: 0.0, upper: 1.0e5 });
        let q = Study::preset("frame40").unwrap();
        assert_eq!(q.inputs.marginal("damper_c3").unwrap(), &Marginal::Uniform { lower: 0.0, upper: 100.0 });
    }

    #[test]
    fn bad_specs_are_refused_by_name() {
        assert!(Study::preset("frame41").unwrap_err().to_string().contains("unknown preset `frame41`"));
        let mut spec = StudySpec { preset: Some("frame40".into()), ..Default::default() };
        spec.inputs.insert("youngs_modulus".into(), Marginal::Normal { mean: 210e9, sd: 100e9 });
        assert!(Study::from_spec(&spec).unwrap_err().to_string().starts_with("inputs.youngs_modulus"));
        let mut spec = StudySpec { preset: Some("frame40".into()), ..Default::default() };
        spec.inputs.insert("stiffness".into(), Marginal::Constant { value: 1.0 });
        assert!(Study::from_spec(&spec).unwrap_err().to_string().contains("unknown input"));
        let spec = StudySpec { preset: Some("frame40".into()), duration_s: Some(-5.0), ..Default::default() };
        assert!(Study::from_spec(&spec).unwrap_err().to_string().starts_with("duration_s"));
        let spec = StudySpec { preset: Some("frame40".into()), modes: Some(0), ..Default::default() };
        assert!(Study::from_spec(&spec).unwrap_err().to_string().starts_with("modes"));
    }
}
