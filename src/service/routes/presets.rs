//! The built-in studies and their default calibration requests, for clients to start from.

use crate::service::error::{ApiError, ProblemDetails};
use crate::service::{AppState, CalibrationRequest};
use crate::study::{DEFAULT_PRESET, PRESETS, Study};
use crate::surrogate::CalibrationOptions;
use axum::Json;
use axum::extract::Path;
use serde::Serialize;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new().routes(routes!(list_presets)).routes(routes!(get_preset))
}

/// A built-in study.
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct Preset {
    pub name: String,
    pub description: String,
    pub floors: usize,
    pub roof_height_m: f64,
    /// Whether a calibration request without `preset` or `structure` calibrates this study.
    pub default: bool,
    /// Natural circular frequencies of the modes kept (rad/s), at the mean inputs.
    pub frequencies_rad_s: Vec<f64>,
    /// The calibration request the defaults amount to, spelled out.
    pub default_calibration: CalibrationRequest,
}

#[derive(Debug, Serialize, ToSchema)]
pub struct PresetList {
    pub presets: Vec<Preset>,
}

fn describe(name: &str) -> Result<Preset, ApiError> {
    let study = Study::preset(name).map_err(|_| ApiError::not_found("preset", name))?;
    let defaults = CalibrationOptions::default();
    let description = if name == "frame40" {
        "The paper's 40-storey steel frame, damper coefficients as printed (N·s/m)"
    } else {
        "The paper's 40-storey steel frame, damper coefficients in kN·s/m"
    };
    Ok(Preset {
        name: name.to_string(),
        description: description.to_string(),
        floors: study.structure.floors(),
        default: name == DEFAULT_PRESET,
        roof_height_m: *study.structure.floor_elevations.last().expect("a structure has floors"),
        frequencies_rad_s: study.modes.frequencies.clone(),
        default_calibration: CalibrationRequest {
            preset: Some(name.to_string()),
            inputs: study.inputs.inputs.iter().map(|i| (i.name.clone(), i.marginal)).collect(),
            modes: Some(study.modes.frequencies.len()),
            duration_s: Some(study.storm.duration),
            time_step_s: Some(study.storm.time_step),
            experiments: Some(defaults.experiments),
            seed: Some(defaults.seed),
            ..CalibrationRequest::default()
        },
    })
}

/// Every preset described, built once (each is an eigen-analysis and a spectral table) off the
/// runtime and kept.
async fn described() -> Result<&'static [Preset], ApiError> {
    static DESCRIBED: tokio::sync::OnceCell<Vec<Preset>> = tokio::sync::OnceCell::const_new();
    let presets = DESCRIBED
        .get_or_try_init(|| async {
            tokio::task::spawn_blocking(|| PRESETS.iter().map(|n| describe(n)).collect::<Result<Vec<_>, _>>())
                .await
                .map_err(ApiError::internal)?
        })
        .await?;
    Ok(presets)
}

/// The built-in studies.
#[utoipa::path(get, path = "/v1/presets", tag = "presets",
    responses((status = 200, description = "Every preset", body = PresetList)))]
async fn list_presets() -> Result<Json<PresetList>, ApiError> {
    Ok(Json(PresetList { presets: described().await?.to_vec() }))
}

/// One built-in study and its default calibration request.
#[utoipa::path(get, path = "/v1/presets/{name}", tag = "presets",
    params(("name" = String, Path, description = "Preset name, e.g. `frame40-kn`")),
    responses(
        (status = 200, description = "The preset", body = Preset),
        (status = 404, description = "No such preset", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn get_preset(Path(name): Path<String>) -> Result<Json<Preset>, ApiError> {
    let found = described().await?.iter().find(|p| p.name == name);
    found.cloned().map(Json).ok_or_else(|| ApiError::not_found("preset", &name))
}
