//! Arguments shared by the commands: the study, the response, the output file.

use crate::analysis::{CertifyOptions, Response, ResponseKind, SpatialKind, SpatialResponse};
use crate::error::{Error, Result};
use crate::structure::spatial::Dof;
use crate::study::{Order, SPATIAL_PRESETS, SpatialStudy, Study, StudySpec, WIND_SPEED};
use crate::uncertainty::{InputModel, Marginal, parse_assignment};
use crate::wind::aerodynamic::Aerodynamics;
use clap::Args;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The study a command runs on: a preset or a spec file, with command-line overrides.
#[derive(Debug, Clone, Args)]
pub struct StudyArgs {
    /// Built-in study: frame40 (dampers as printed, N·s/m), frame40-kn (the same numbers in kN·s/m),
    /// or the three-dimensional frame40-3d (`modes`, `simulate` and `sample-peaks` only).
    #[arg(long, default_value = "frame40-kn", conflicts_with = "spec")]
    pub preset: String,
    /// A study file (JSON): preset or custom structure, input marginals, wind, modes, duration.
    #[arg(long)]
    pub spec: Option<PathBuf>,
    /// Hold an input at a value, e.g. --fix wind_speed=35 (repeatable).
    #[arg(long = "fix", value_name = "NAME=VALUE")]
    pub fix: Vec<String>,
    /// Storm duration (s).
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Time step (s).
    #[arg(long, allow_negative_numbers = true)]
    pub time_step: Option<f64>,
    /// Retained modes.
    #[arg(long)]
    pub modes: Option<usize>,
    /// Three-dimensional studies: across-wind and torsional loads from this wind-tunnel data file
    /// (docs/wind-tunnel-data.md) instead of the published model.
    #[arg(long, value_name = "FILE")]
    pub wind_tunnel: Option<PathBuf>,
}

impl StudyArgs {
    /// Reads the spec (file or preset), applies the command-line overrides and the fixed inputs.
    pub fn study(&self) -> Result<Study> {
        if self.wind_tunnel.is_some() {
            return Err(Error::invalid("wind-tunnel", "applies to a three-dimensional study (frame40-3d) only"));
        }
        let mut study = Study::from_spec(&self.spec()?)?;
        for assignment in &self.fix {
            let (name, value) = parse_assignment(assignment)?;
            study.inputs = study.inputs.with_fixed(&name, value)?;
        }
        Ok(study)
    }

    /// The three-dimensional study of the preset, with the wake loads of the published model or of
    /// `--wind-tunnel`, the command line's overrides and fixed inputs applied.
    pub fn spatial_study(&self) -> Result<SpatialStudy> {
        // Fixed before the building is made: an eccentricity moves its centres of mass.
        let mut spec = self.spec()?;
        for assignment in &self.fix {
            let (name, value) = parse_assignment(assignment)?;
            spec.inputs.insert(name, Marginal::Constant { value });
        }
        SpatialStudy::from_spec(&spec, self.aerodynamics()?)
    }

    /// The wake loads: the published model, or the wind-tunnel file's (its refusals name the file).
    pub fn aerodynamics(&self) -> Result<Aerodynamics> {
        let Some(path) = &self.wind_tunnel else { return Ok(Aerodynamics::Published) };
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::invalid("wind-tunnel", format!("cannot read {}: {e}", path.display())))?;
        Aerodynamics::from_json(&text).map_err(|e| match e {
            Error::Invalid { field, reason } => {
                Error::invalid(format!("wind-tunnel {}: {field}", path.display()), reason)
            }
            other => other,
        })
    }

    /// Whether the study is a three-dimensional building: a preset, or a spec file with a
    /// `spatial_structure` or a three-dimensional preset (a spec that cannot be read is left to the
    /// plane study's refusal).
    pub fn is_spatial(&self) -> bool {
        match &self.spec {
            None => SPATIAL_PRESETS.contains(&self.preset.as_str()),
            Some(_) => self.spec().is_ok_and(|spec| {
                spec.spatial_structure.is_some() || spec.preset.as_deref().is_some_and(|p| SPATIAL_PRESETS.contains(&p))
            }),
        }
    }

    /// The spec (file or preset) with the command line's storm and modes.
    fn spec(&self) -> Result<StudySpec> {
        let mut spec = match &self.spec {
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .map_err(|e| Error::invalid("spec", format!("cannot read {}: {e}", path.display())))?;
                serde_json::from_str::<StudySpec>(&text)
                    .map_err(|e| Error::invalid("spec", format!("{}: {e}", path.display())))?
            }
            None => StudySpec { preset: Some(self.preset.clone()), ..Default::default() },
        };
        if self.duration.is_some() {
            spec.duration_s = self.duration;
        }
        if self.time_step.is_some() {
            spec.time_step_s = self.time_step;
        }
        if self.modes.is_some() {
            spec.modes = self.modes;
        }
        Ok(spec)
    }
}

/// A metamodel sampled with some inputs held, as exceedance curves and profiles take it.
#[derive(Debug, Clone, Args)]
pub struct SamplingArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// Storms sampled from the metamodel, one input sample each.
    #[arg(long, default_value_t = 10_000)]
    pub samples: usize,
    /// Hold the mean wind speed (m/s): an answer conditional on it.
    #[arg(long, allow_negative_numbers = true)]
    pub wind_speed: Option<f64>,
    /// Hold any input, e.g. --fix damping_ratio=0.02 (repeatable).
    #[arg(long = "fix", value_name = "NAME=VALUE")]
    pub fix: Vec<String>,
}

impl SamplingArgs {
    /// The inputs held by `--wind-speed` and the `--fix NAME=VALUE` assignments, by name, as an
    /// analysis's options take them; an input held twice is refused.
    pub fn fixed(&self) -> Result<BTreeMap<String, f64>> {
        let mut fixed = BTreeMap::new();
        let wind_speed = self.wind_speed.map(|v| (WIND_SPEED.to_string(), v));
        let assignments = self.fix.iter().map(|a| parse_assignment(a)).collect::<Result<Vec<_>>>()?;
        for (name, value) in wind_speed.into_iter().chain(assignments) {
            if fixed.insert(name.clone(), value).is_some() {
                return Err(Error::invalid("fix", format!("`{name}` is held twice")));
            }
        }
        Ok(fixed)
    }

    /// The study's input model with the wind speed and the `--fix NAME=VALUE` assignments held,
    /// checked as every analysis checks held inputs (errors name `fixed.<input>`).
    pub fn held_inputs(&self, study: &Study) -> Result<InputModel> {
        crate::analysis::held_inputs(study, &self.fixed()?)
    }
}

/// Which peak response a command is about.
#[derive(Debug, Clone, Args)]
pub struct ResponseArgs {
    /// Floor of the response (default: the roof).
    #[arg(long)]
    pub floor: Option<usize>,
    /// For damper_force and damper_stroke: the largest among the dampers of this coefficient
    /// group (1-based) instead of one floor's damper.
    #[arg(long, conflicts_with = "floor")]
    pub group: Option<usize>,
    /// The response: displacement, drift, acceleration, rms_acceleration, damper_force or
    /// damper_stroke (the damper in the storey below the floor, or a group's with --group).
    #[arg(long, default_value = "displacement", conflicts_with = "drift")]
    pub response: String,
    /// The inter-storey drift below the floor (the same as --response drift).
    #[arg(long)]
    pub drift: bool,
    /// Three-dimensional studies: the direction of a response at the centre of mass, x, y or
    /// rotation (corner_acceleration and rms_corner_acceleration take none).
    #[arg(long, value_parser = ["x", "y", "rotation"])]
    pub direction: Option<String>,
}

impl ResponseArgs {
    /// The response of a plane study.
    pub fn response(&self, study: &Study) -> Result<Response> {
        if self.direction.is_some() {
            return Err(Error::invalid("direction", "a plane frame moves along the wind only; it takes no direction"));
        }
        let kind = if self.drift { ResponseKind::Drift } else { ResponseKind::parse(&self.response)? };
        kind.located(self.floor, self.group, &study.structure)
    }

    /// The response of a three-dimensional study.
    pub fn spatial_response(&self, study: &SpatialStudy) -> Result<SpatialResponse> {
        if self.group.is_some() {
            return Err(Error::invalid("group", "damper responses of a three-dimensional building are not read yet"));
        }
        let kind = if self.drift { SpatialKind::Drift } else { SpatialKind::parse(&self.response)? };
        let direction = match self.direction.as_deref() {
            None => None,
            Some("x") => Some(Dof::X),
            Some("y") => Some(Dof::Y),
            Some(_) => Some(Dof::Rotation),
        };
        SpatialResponse::located(kind, self.floor, direction, &study.structure)
    }
}

/// A certified answer: storms run through the reference model as well, so that the probabilities
/// carry the metamodel's own error.
#[derive(Debug, Clone, Args)]
pub struct CertifyArgs {
    /// Certify the answer with N storms run through both the reference model and the metamodel
    /// (unbiased for the reference model, its band holding the metamodel's error; at most 5 000).
    #[arg(long, value_name = "N")]
    pub certify: Option<usize>,
    /// The reference model of --certify: reduced (the retained modes) or full (every floor).
    #[arg(long, default_value = "reduced", value_parser = ["reduced", "full"], requires = "certify")]
    pub certify_order: String,
}

impl CertifyArgs {
    /// The certification asked for, if any.
    pub fn options(&self) -> Option<CertifyOptions> {
        let order = if self.certify_order == "full" { Order::Full } else { Order::Reduced };
        self.certify.map(|reference_storms| CertifyOptions { reference_storms, order })
    }
}

/// The seed, the band's level and the output of an analysis command.
#[derive(Debug, Clone, Args)]
pub struct AnalysisArgs {
    /// Seed of the input samples and of the storms' wind.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Confidence level of the bands and intervals.
    #[arg(long, default_value_t = 0.95)]
    pub confidence: f64,
    /// Print the answer as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The climate `--climate` gives as JSON, or the metamodel's own wind-speed law.
pub fn climate_arg(text: Option<&str>, study: &crate::study::Study) -> Result<crate::uncertainty::Marginal> {
    let spec = text
        .map(serde_json::from_str::<crate::analysis::ClimateSpec>)
        .transpose()
        .map_err(|e| Error::invalid("climate", e.to_string()))?;
    crate::analysis::climate_or_own(spec.as_ref(), study)
}

/// The format of `--out` by its extension, one of `allowed`.
pub fn out_format(out: Option<&std::path::Path>, allowed: &[&str]) -> Result<Option<String>> {
    let Some(path) = out else { return Ok(None) };
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if allowed.contains(&e) => Ok(Some(e.to_string())),
        _ => Err(Error::invalid("out", format!("the file must end in .{}", allowed.join(", .")))),
    }
}

/// Writes an output file, naming it in the error.
pub fn write_out(path: &std::path::Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::invalid("out", format!("{}: {e}", path.display())))
}

/// A command's answer: written to `--out` in its format (JSON, or what `render` makes of the
/// other formats), printed as JSON with `--json`, else as `table`.
pub fn answer<T: serde::Serialize>(
    value: &T,
    json: bool,
    out: Option<(&std::path::Path, String)>,
    render: impl FnOnce(&str) -> String,
    table: impl FnOnce() -> String,
) -> Result<String> {
    let as_json = || serde_json::to_string_pretty(value).expect("plain JSON");
    if let Some((path, format)) = out {
        let text = if format == "json" { as_json() } else { render(&format) };
        write_out(path, &text)?;
    }
    Ok(if json { as_json() } else { table() })
}
