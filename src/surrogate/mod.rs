//! PC-NARX metamodels (sections 3.2-3.3): NARX dynamics per retained mode whose coefficients are
//! sparse polynomial-chaos expansions of the uncertain inputs.

pub mod assembly;
pub mod batch;
mod calibrate;
mod cost;
mod damper_law;
mod design;
pub mod identify;
pub mod lars;
mod metamodel;
pub mod narx;
mod options;
mod parametrization;
pub mod pce;
pub mod phases;
mod prediction;
pub use prediction::PEAK_BATCH;
mod refine;

pub use batch::{BatchInput, BatchWorkspace, ModalScales, MotionSink, Reduction};
pub use calibrate::calibrate;
pub use cost::{CalibrationCost, MAX_PCE_BASIS};
pub use damper_law::{DamperLaw, KNEE_FRACTION};
pub use design::{Design, design};
pub use metamodel::{
    CalibrationSummary, Metamodel, ModalBasis, ModeDiagnostics, ModeModel, StageSeconds, StaticResponse,
};
pub use options::{CalibrationOptions, MAX_EXPERIMENTS, WindCoverage};
pub use parametrization::Parametrization;
pub use refine::{Refinement, RefinementOutcome, RefinementSummary, refine};
