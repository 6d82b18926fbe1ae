//! The study a stored metamodel answers for, in a few hundred bytes: what a client needs to ask
//! it questions (floors, damper groups, inputs with their laws and calibrated ranges) without
//! reading the coefficients.

use super::metamodels::load;
use crate::analysis::ResponseKind;
use crate::service::AppState;
use crate::service::error::{ApiError, ProblemDetails};
use crate::uncertainty::Marginal;
use axum::Json;
use axum::extract::{Path, State};
use serde::Serialize;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new().routes(routes!(get_study))
}

/// A metamodel's study: the building, the storm grid and the uncertain inputs.
#[derive(Debug, Serialize, ToSchema)]
pub struct Study {
    pub metamodel_id: String,
    /// The study's name (a preset or `custom`).
    pub preset: String,
    pub floors: usize,
    pub roof_height_m: f64,
    /// Damper coefficient groups (0: no dampers), for requests that name a `group`.
    pub damper_groups: usize,
    /// Natural circular frequencies of the retained modes at the mean inputs (rad/s).
    pub frequencies_rad_s: Vec<f64>,
    pub duration_s: f64,
    pub time_step_s: f64,
    /// The responses an analysis may ask for: the damper ones only where there are dampers.
    pub responses: Vec<ResponseKind>,
    pub inputs: Vec<StudyInput>,
}

/// One uncertain input.
#[derive(Debug, Serialize, ToSchema)]
pub struct StudyInput {
    /// The name that `fixed` and the sensitivity indices use.
    pub name: String,
    pub marginal: Marginal,
    /// The lowest and highest value among the calibration's experiments: where the expansions
    /// were fitted; a value held fixed outside it is an extrapolation.
    pub calibrated_range: [f64; 2],
}

/// The study of a stored metamodel: floors, damper groups, storm grid, and each uncertain input's
/// law and calibrated range (where a value held fixed stays inside what the experiments covered).
#[utoipa::path(get, path = "/v1/metamodels/{id}/study", tag = "metamodels",
    params(("id" = String, Path, description = "Metamodel id")),
    responses(
        (status = 200, description = "The study", body = Study),
        (status = 404, description = "No such metamodel", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn get_study(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Study>, ApiError> {
    let loaded = load(&state, &id).await?;
    let study = tokio::task::spawn_blocking(move || -> crate::error::Result<Study> {
        let (metamodel, study) = (&loaded.metamodel, &loaded.study);
        let inputs = study
            .inputs
            .inputs
            .iter()
            .map(|input| {
                Ok(StudyInput {
                    name: input.name.clone(),
                    marginal: input.marginal,
                    calibrated_range: metamodel.calibrated_range(study, &input.name)?,
                })
            })
            .collect::<crate::error::Result<Vec<_>>>()?;
        let damper_groups = study.structure.damper_groups();
        Ok(Study {
            metamodel_id: id,
            preset: study.name.clone(),
            floors: study.structure.floors(),
            roof_height_m: study.structure.floor_elevations.last().copied().unwrap_or(0.0),
            damper_groups,
            frequencies_rad_s: study.modes.frequencies.clone(),
            duration_s: study.storm.duration,
            time_step_s: study.storm.time_step,
            responses: ResponseKind::ALL
                .into_iter()
                .filter(|kind| damper_groups > 0 || kind.of_group(1).is_err())
                .collect(),
            inputs,
        })
    })
    .await
    .map_err(ApiError::internal)??;
    Ok(Json(study))
}
