//! The service's vocabulary of work: what kind of work an operation does, and a queued job as
//! the typed request it runs. Routes build a [`Job`] and queue it; the worker reads it back with
//! [`Job::stored`] and matches it exhaustively, so that a new kind of work cannot be queued
//! without a worker that runs it.

use super::analyses::{AnalysisJob, AnalysisRequest};
use super::exceedance::ExceedanceJob;
use super::requests::{CalibrationRequest, ValidationJob};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// What kind of work an operation does (the stored job's `kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum OperationKind {
    /// Fitting a metamodel on a Latin-hypercube design of reference runs.
    Calibration,
    /// Comparing a metamodel with the reference model on fresh storms.
    Validation,
    /// An exceedance curve of a peak response.
    Exceedance,
    /// An annual curve under a wind climate.
    Hazard,
    /// Fragility curves over the wind speed.
    Fragility,
    /// Sobol indices of a peak response.
    Sensitivity,
    /// A serviceability check against criteria.
    Serviceability,
    /// A return level swept over one input's values.
    Sweep,
}

impl OperationKind {
    /// The kind's name, as stored and as the API spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            OperationKind::Calibration => "calibration",
            OperationKind::Validation => "validation",
            OperationKind::Exceedance => "exceedance",
            OperationKind::Hazard => "hazard",
            OperationKind::Fragility => "fragility",
            OperationKind::Sensitivity => "sensitivity",
            OperationKind::Serviceability => "serviceability",
            OperationKind::Sweep => "sweep",
        }
    }
}

/// A queued job: its kind (the tag, stored as the job's `kind`) and the request it runs (stored
/// as the job's `request`, in the same JSON that was queued).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "kind", content = "request", rename_all = "snake_case")]
pub enum Job {
    /// `POST /v1/calibrations`.
    Calibration(Box<CalibrationRequest>),
    /// `POST /v1/metamodels/{id}/validations`.
    Validation(ValidationJob),
    /// A large or certified `POST /v1/metamodels/{id}/exceedance`.
    Exceedance(ExceedanceJob),
    /// A large or certified `POST /v1/metamodels/{id}/hazard`.
    Hazard(AnalysisJob),
    /// A large or certified `POST /v1/metamodels/{id}/fragility`.
    Fragility(AnalysisJob),
    /// A large `POST /v1/metamodels/{id}/sensitivity`.
    Sensitivity(AnalysisJob),
    /// A large or certified `POST /v1/metamodels/{id}/serviceability`.
    Serviceability(AnalysisJob),
    /// A large `POST /v1/metamodels/{id}/sweep`.
    Sweep(AnalysisJob),
}

impl Job {
    /// An analysis of a stored metamodel, as the job of its kind.
    pub fn analysis(metamodel_id: String, request: AnalysisRequest) -> Job {
        let job = AnalysisJob { metamodel_id, request };
        match &job.request {
            AnalysisRequest::Hazard(_) => Job::Hazard(job),
            AnalysisRequest::Fragility(_) => Job::Fragility(job),
            AnalysisRequest::Sensitivity(_) => Job::Sensitivity(job),
            AnalysisRequest::Serviceability(_) => Job::Serviceability(job),
            AnalysisRequest::Sweep(_) => Job::Sweep(job),
        }
    }

    /// The job's kind.
    pub fn kind(&self) -> OperationKind {
        match self {
            Job::Calibration(_) => OperationKind::Calibration,
            Job::Validation(_) => OperationKind::Validation,
            Job::Exceedance(_) => OperationKind::Exceedance,
            Job::Hazard(_) => OperationKind::Hazard,
            Job::Fragility(_) => OperationKind::Fragility,
            Job::Sensitivity(_) => OperationKind::Sensitivity,
            Job::Serviceability(_) => OperationKind::Serviceability,
            Job::Sweep(_) => OperationKind::Sweep,
        }
    }

    /// The endpoint whose `Idempotency-Key`s this job's key is compared with.
    pub fn idempotency_scope(&self) -> &'static str {
        match self {
            Job::Calibration(_) => "calibrations",
            Job::Validation(_) => "validations",
            other => other.kind().as_str(),
        }
    }

    /// The stored metamodel the job works on (none for a calibration, which makes one).
    pub fn metamodel_id(&self) -> Option<&str> {
        match self {
            Job::Calibration(_) => None,
            Job::Validation(job) => Some(&job.metamodel_id),
            Job::Exceedance(job) => Some(&job.metamodel_id),
            Job::Hazard(job)
            | Job::Fragility(job)
            | Job::Sensitivity(job)
            | Job::Serviceability(job)
            | Job::Sweep(job) => Some(&job.metamodel_id),
        }
    }

    /// The request as the queue stores it: the JSON of the variant's request alone.
    pub fn request_json(&self) -> String {
        match self {
            Job::Calibration(request) => serde_json::to_string(request),
            Job::Validation(job) => serde_json::to_string(job),
            Job::Exceedance(job) => serde_json::to_string(job),
            Job::Hazard(job)
            | Job::Fragility(job)
            | Job::Sensitivity(job)
            | Job::Serviceability(job)
            | Job::Sweep(job) => serde_json::to_string(job),
        }
        .expect("a job serialises")
    }

    /// A stored job read back from its `kind` and `request` columns. An analysis whose request
    /// names another analysis than its kind is refused.
    pub fn stored(kind: &str, request: &str) -> Result<Job> {
        let kind_json = serde_json::to_string(kind).expect("a string serialises");
        let tagged = format!(r#"{{"kind":{kind_json},"request":{request}}}"#);
        let job: Job = serde_json::from_str(&tagged)
            .map_err(|e| Error::Internal(format!("a stored job of kind `{kind}` does not read back: {e}")))?;
        if let Job::Hazard(analysis)
        | Job::Fragility(analysis)
        | Job::Sensitivity(analysis)
        | Job::Serviceability(analysis)
        | Job::Sweep(analysis) = &job
            && analysis_kind(&analysis.request) != job.kind()
        {
            return Err(Error::Internal(format!("a stored job of kind `{kind}` holds another analysis")));
        }
        Ok(job)
    }
}

/// The kind of operation an analysis request runs as.
fn analysis_kind(request: &AnalysisRequest) -> OperationKind {
    match request {
        AnalysisRequest::Hazard(_) => OperationKind::Hazard,
        AnalysisRequest::Fragility(_) => OperationKind::Fragility,
        AnalysisRequest::Sensitivity(_) => OperationKind::Sensitivity,
        AnalysisRequest::Serviceability(_) => OperationKind::Serviceability,
        AnalysisRequest::Sweep(_) => OperationKind::Sweep,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::service::analyses::SensitivityRequest;

    /// A job reads back from the columns it is stored in as the same job, whatever its kind.
    #[test]
    fn a_job_reads_back_from_its_columns() {
        let jobs = [
            Job::Calibration(Box::new(CalibrationRequest { experiments: Some(12), ..Default::default() })),
            Job::analysis("m".into(), AnalysisRequest::Sensitivity(SensitivityRequest::default())),
        ];
        for job in jobs {
            let back = Job::stored(job.kind().as_str(), &job.request_json()).unwrap();
            assert_eq!((back.kind(), back.request_json()), (job.kind(), job.request_json()));
        }
    }

    /// A stored analysis whose request is of another kind is an error, not another analysis.
    #[test]
    fn an_analysis_under_another_kind_is_refused() {
        let job = Job::analysis("m".into(), AnalysisRequest::Sensitivity(SensitivityRequest::default()));
        let error = Job::stored("hazard", &job.request_json()).unwrap_err();
        assert!(error.to_string().contains("another analysis"), "{error}");
        assert!(Job::stored("sorcery", "{}").is_err());
    }
}
