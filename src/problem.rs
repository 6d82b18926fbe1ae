//! One study: a structure, its uncertain inputs by name, the wind site, the damper law and the storm
//! grid, and the reference runs over them. The paper's case study comes as two presets.
//!
//! The input names are the same on the command line, in files and over HTTP: `youngs_modulus` (Pa),
//! `mass_factor`, `damping_ratio` (shared by all modes), `damper_c1` … `damper_cG` (N·(s/m)^α, one
//! per damper group from the ground up) and `wind_speed` (m/s at the station, 10 m).

use crate::cancel::Never;
use crate::dynamics::{Dampers, FullSystem, integrate_full, integrate_reduced};
use crate::error::{Error, Result};
use crate::structure::{CustomStructure, Modes, Structure, frame40};
use crate::uncertainty::{Input, InputModel, Marginal, Rng, rng_from_seed, stream_seed};
use crate::wind::{CoarseModalForces, ModalForces, ModalWind, StormGrid, WindLoads, WindSite, Workspace};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::Instant;

/// The built-in studies: the paper's frame with damper coefficients as printed (N·s/m) and the same
/// numbers in kN·s/m, where the dampers really act.
pub const PRESETS: [&str; 2] = ["frame40", "frame40-kn"];

/// A study as it arrives from a file or a request; every field is optional, with the paper's values
/// as defaults.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(default, deny_unknown_fields)]
pub struct ProblemSpec {
    /// A preset name; ignored for the structure when `structure` is given.
    pub preset: Option<String>,
    /// A custom structure instead of the preset's.
    pub structure: Option<CustomStructure>,
    /// Marginals that replace the defaults, by input name.
    pub inputs: BTreeMap<String, Marginal>,
    pub wind: Option<WindSite>,
    /// Exponent α of the damper law (0.38 in the paper).
    pub damper_exponent: Option<f64>,
    /// Retained modes N_m (3 in the paper).
    pub modes: Option<usize>,
    /// Storm duration T (s), 900 in the paper.
    pub duration_s: Option<f64>,
    /// Time step Δt (s), 0.01 in the paper.
    pub time_step_s: Option<f64>,
}

/// The physical values of one sample of the inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalParameters {
    pub youngs_modulus: f64,
    pub mass_factor: f64,
    pub damping_ratio: f64,
    pub damper_coefficients: Vec<f64>,
    pub wind_speed: f64,
}

/// How the wind of a reference run is generated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum WindPath {
    /// Every floor's speed, then Q = Φᵀ f.
    Field,
    /// The retained modes' forces directly from Φᵀ S_f Φ (equal in law, much cheaper).
    Modal,
}

/// Which reference model integrates the storm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Order {
    Reduced,
    Full,
}

/// One storm through the reference model.
#[derive(Debug, Clone)]
pub struct StormRun {
    /// Roof displacement history (m), static part included.
    pub roof: Vec<f64>,
    /// Modal forces that drove it (absent for full-order runs from the field).
    pub modal_forces: Option<ModalForces>,
    /// Modal displacement histories of a reduced-order run.
    pub modal_displacements: Option<Vec<Vec<f64>>>,
    pub wind_seconds: f64,
    pub integration_seconds: f64,
}

impl StormRun {
    /// Peak absolute roof displacement (m).
    pub fn peak(&self) -> f64 {
        self.roof.iter().fold(0.0, |m, x| m.max(x.abs()))
    }
}

/// A validated study.
#[derive(Debug, Clone)]
pub struct Problem {
    pub name: String,
    /// The spec it was built from (inputs and storm as given, before later changes).
    spec: ProblemSpec,
    pub structure: Structure,
    /// The retained modes at the reference stiffness and unit mass factor.
    pub modes: Modes,
    /// All N modes, for the classical damping of the full-order model.
    pub all_modes: Modes,
    pub inputs: InputModel,
    pub wind: WindLoads,
    /// The modal-force fast path for `modes`, its spectral table built once.
    pub modal_wind: ModalWind,
    pub damper_exponent: f64,
    pub storm: StormGrid,
}

fn default_inputs(structure: &Structure, damper_scale: f64) -> InputModel {
    let mut inputs = vec![
        Input {
            name: "youngs_modulus".into(),
            marginal: Marginal::Lognormal {
                mean: structure.reference_youngs_modulus,
                sd: structure.reference_youngs_modulus * 15.0 / 210.0,
            },
        },
        Input { name: "mass_factor".into(), marginal: Marginal::Lognormal { mean: 1.0, sd: 0.05 } },
        Input { name: "damping_ratio".into(), marginal: Marginal::Lognormal { mean: 0.015, sd: 0.005 } },
    ];
    for g in 0..structure.damper_groups() {
        inputs.push(Input {
            name: format!("damper_c{}", g + 1),
            marginal: Marginal::Uniform { lower: 0.0, upper: 100.0 * damper_scale },
        });
    }
    inputs.push(Input { name: "wind_speed".into(), marginal: Marginal::Frechet { mean: 30.0, sd: 3.5 } });
    InputModel { inputs }
}

/// Most modes a study retains: the modal wind costs the square of the modes per storm and the
/// coupled NARX dictionaries grow with them; the paper's building needs three.
pub const MAX_MODES: usize = 10;

/// Every physical input is non-negative; these must also stay away from zero.
const POSITIVE_INPUTS: [&str; 3] = ["youngs_modulus", "mass_factor", "wind_speed"];

fn check_admissible(input: &Input) -> Result<()> {
    let (lower, _) = input.marginal.support();
    let positive = POSITIVE_INPUTS.contains(&input.name.as_str());
    if lower < 0.0 || (positive && input.marginal.contains(0.0)) {
        let bound = if positive { "positive" } else { "non-negative" };
        return Err(Error::invalid(
            format!("inputs.{}", input.name),
            format!(
                "must be {bound}, but its distribution reaches {lower}; choose one that stays {bound} (lognormal, uniform)"
            ),
        ));
    }
    Ok(())
}

impl Problem {
    /// A preset study by name.
    pub fn preset(name: &str) -> Result<Problem> {
        Problem::from_spec(&ProblemSpec { preset: Some(name.to_string()), ..Default::default() })
    }

    pub fn from_spec(spec: &ProblemSpec) -> Result<Problem> {
        let (name, damper_scale) = match spec.preset.as_deref() {
            Some("frame40") => ("frame40", 1.0),
            Some("frame40-kn") => ("frame40-kn", 1000.0),
            Some(other) => {
                return Err(Error::invalid(
                    "preset",
                    format!("unknown preset `{other}`; the presets are {}", PRESETS.join(", ")),
                ));
            }
            None if spec.structure.is_some() => ("custom", 1.0),
            None => return Err(Error::invalid("preset", "give a preset name or a custom structure")),
        };
        let (structure, name) = match &spec.structure {
            Some(custom) => {
                (custom.build()?, if spec.preset.is_some() { format!("{name}+custom") } else { "custom".into() })
            }
            None => (frame40()?, name.to_string()),
        };
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
        let all_modes = Modes::of(&structure, structure.floors())?;
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
        Ok(Problem {
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
    pub fn resolved_spec(&self) -> ProblemSpec {
        let mut spec = self.spec.clone();
        spec.inputs = self.inputs.inputs.iter().map(|i| (i.name.clone(), i.marginal)).collect();
        spec.duration_s = Some(self.storm.duration);
        spec.time_step_s = Some(self.storm.time_step);
        spec.modes = Some(self.modes.count());
        spec
    }

    /// The same study on another storm grid.
    pub fn with_storm(mut self, duration: f64, time_step: f64) -> Result<Problem> {
        self.storm = StormGrid::new(duration, time_step, &self.wind.site)?;
        Ok(self)
    }

    /// Reads a sample (values in the input model's order) as physical parameters.
    pub fn parameters(&self, x: &[f64]) -> Result<PhysicalParameters> {
        self.inputs.check_sample(x)?;
        let value = |name: &str| -> Result<f64> { Ok(x[self.inputs.index_of(name)?]) };
        let damper_coefficients =
            (1..=self.structure.damper_groups()).map(|g| value(&format!("damper_c{g}"))).collect::<Result<Vec<_>>>()?;
        Ok(PhysicalParameters {
            youngs_modulus: value("youngs_modulus")?,
            mass_factor: value("mass_factor")?,
            damping_ratio: value("damping_ratio")?,
            damper_coefficients,
            wind_speed: value("wind_speed")?,
        })
    }

    /// Stiffness factor κ = E / E_ref of a sample.
    pub fn stiffness_factor(&self, p: &PhysicalParameters) -> f64 {
        p.youngs_modulus / self.structure.reference_youngs_modulus
    }

    /// The retained modes of a sample: shapes fixed, ω ∝ √(κ/μ), M_m ∝ μ.
    pub fn sample_modes(&self, p: &PhysicalParameters) -> Modes {
        self.modes.scaled(self.stiffness_factor(p), p.mass_factor)
    }

    pub fn dampers(&self, p: &PhysicalParameters) -> Result<Dampers> {
        Dampers::new(&self.structure, &p.damper_coefficients, self.damper_exponent)
    }

    /// A storm's modal forces on the wind's generation grid, by the fast path or the full field,
    /// with the transforms of `workspace`.
    pub fn coarse_forces(
        &self,
        p: &PhysicalParameters,
        path: WindPath,
        workspace: &mut Workspace,
        rng: &mut Rng,
    ) -> Result<CoarseModalForces> {
        match path {
            WindPath::Modal => self.modal_wind.simulate(p.wind_speed, self.storm.duration, workspace, rng),
            WindPath::Field => {
                self.wind.projected_field(p.wind_speed, self.modes.shapes.as_ref(), self.storm.duration, workspace, rng)
            }
        }
    }

    /// A storm's modal forces on the storm's grid.
    pub fn modal_forces(&self, p: &PhysicalParameters, path: WindPath, rng: &mut Rng) -> Result<ModalForces> {
        Ok(self.coarse_forces(p, path, &mut Workspace::default(), rng)?.on_grid(&self.storm))
    }

    /// Sample k of a run seeded with `seed`: its physical parameters and its storm's modal forces on
    /// the generation grid. The storm depends only on (seed, k), whichever thread draws it and
    /// however many there are. `workspace` holds the wind's transforms; keep one per thread.
    pub fn sample_storm(
        &self,
        x: &[f64],
        path: WindPath,
        seed: u64,
        k: usize,
        workspace: &mut Workspace,
    ) -> Result<(PhysicalParameters, CoarseModalForces)> {
        let p = self.parameters(x)?;
        let forces = self.coarse_forces(&p, path, workspace, &mut rng_from_seed(stream_seed(seed, k as u64)))?;
        Ok((p, forces))
    }

    /// One storm through the reference model (not cancellable: for the command line). Full-order
    /// runs always use the floor field.
    pub fn reference_run(&self, x: &[f64], order: Order, path: WindPath, rng: &mut Rng) -> Result<StormRun> {
        let p = self.parameters(x)?;
        let dampers = self.dampers(&p)?;
        let dt = self.storm.time_step;
        match order {
            Order::Reduced => {
                let started = Instant::now();
                let forces = self.modal_forces(&p, path, rng)?;
                let wind_seconds = started.elapsed().as_secs_f64();
                let started = Instant::now();
                let response =
                    integrate_reduced(&self.sample_modes(&p), p.damping_ratio, &dampers, &forces, dt, &Never)?;
                let integration_seconds = started.elapsed().as_secs_f64();
                Ok(StormRun {
                    roof: response.roof(),
                    modal_forces: Some(forces),
                    modal_displacements: Some(response.displacements),
                    wind_seconds,
                    integration_seconds,
                })
            }
            Order::Full => {
                let started = Instant::now();
                let forces = self.wind.floor_forces(p.wind_speed, &self.storm, rng)?;
                let wind_seconds = started.elapsed().as_secs_f64();
                let started = Instant::now();
                let system = FullSystem::new(
                    &self.structure,
                    &self.all_modes,
                    self.stiffness_factor(&p),
                    p.mass_factor,
                    p.damping_ratio,
                );
                let response = integrate_full(&system, &dampers, &forces, dt, &Never)?;
                let integration_seconds = started.elapsed().as_secs_f64();
                let roof = response.displacements.last().cloned().unwrap_or_default();
                Ok(StormRun { roof, modal_forces: None, modal_displacements: None, wind_seconds, integration_seconds })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_have_the_papers_eight_inputs() {
        let p = Problem::preset("frame40-kn").unwrap();
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
        let q = Problem::preset("frame40").unwrap();
        assert_eq!(q.inputs.marginal("damper_c3").unwrap(), &Marginal::Uniform { lower: 0.0, upper: 100.0 });
    }

    #[test]
    fn bad_specs_are_refused_by_name() {
        assert!(Problem::preset("frame41").unwrap_err().to_string().contains("unknown preset `frame41`"));
        let mut spec = ProblemSpec { preset: Some("frame40".into()), ..Default::default() };
        spec.inputs.insert("youngs_modulus".into(), Marginal::Normal { mean: 210e9, sd: 15e9 });
        assert!(Problem::from_spec(&spec).unwrap_err().to_string().starts_with("inputs.youngs_modulus"));
        let mut spec = ProblemSpec { preset: Some("frame40".into()), ..Default::default() };
        spec.inputs.insert("stiffness".into(), Marginal::Constant { value: 1.0 });
        assert!(Problem::from_spec(&spec).unwrap_err().to_string().contains("unknown input"));
        let spec = ProblemSpec { preset: Some("frame40".into()), duration_s: Some(-5.0), ..Default::default() };
        assert!(Problem::from_spec(&spec).unwrap_err().to_string().starts_with("duration_s"));
        let spec = ProblemSpec { preset: Some("frame40".into()), modes: Some(0), ..Default::default() };
        assert!(Problem::from_spec(&spec).unwrap_err().to_string().starts_with("modes"));
    }
}
