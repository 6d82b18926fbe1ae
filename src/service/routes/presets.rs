//! The built-in studies and their default calibration requests, for clients to start from.

use crate::problem::{PRESETS, Problem};
use crate::service::AppState;
use crate::service::error::ApiError;
use axum::extract::Path;
use axum::routing::get;
use axum::{Json, Router};
use serde_json::{Value, json};

pub fn router() -> Router<AppState> {
    Router::new().route("/v1/presets", get(list)).route("/v1/presets/{name}", get(one))
}

fn describe(name: &str) -> Result<Value, ApiError> {
    let problem = Problem::preset(name).map_err(|_| ApiError::not_found("preset", name))?;
    let inputs: serde_json::Map<String, Value> = problem
        .inputs
        .inputs
        .iter()
        .map(|i| (i.name.clone(), serde_json::to_value(i.marginal).expect("a marginal serialises")))
        .collect();
    Ok(json!({
        "name": name,
        "description": if name == "frame40" {
            "The paper's 40-storey steel frame, damper coefficients as printed (N·s/m)"
        } else {
            "The paper's 40-storey steel frame, damper coefficients in kN·s/m"
        },
        "floors": problem.structure.floors(),
        "roof_height_m": problem.structure.floor_elevations.last(),
        "frequencies_rad_s": problem.modes.frequencies,
        "default_calibration": {
            "preset": name, "experiments": 200, "duration_s": 900.0, "time_step_s": 0.01, "modes": 3, "seed": 1,
            "inputs": inputs,
        },
    }))
}

async fn list() -> Result<Json<Value>, ApiError> {
    Ok(Json(json!({"presets": PRESETS.iter().map(|n| describe(n)).collect::<Result<Vec<_>, _>>()?})))
}

async fn one(Path(name): Path<String>) -> Result<Json<Value>, ApiError> {
    Ok(Json(describe(&name)?))
}
