//! PC-NARX metamodels (sections 3.2-3.3): NARX dynamics per retained mode whose coefficients are
//! sparse polynomial-chaos expansions of the uncertain inputs.

pub mod batch;
mod calibrate;
mod cost;
pub mod identify;
pub mod lars;
mod metamodel;
pub mod narx;
mod parametrization;
pub mod pce;
pub mod phases;
mod simd;

pub use batch::{ForceSource, LANES};
pub use calibrate::{CalibrationOptions, MAX_EXPERIMENTS, ModeDiagnostics, Observer, Progress, Silent, calibrate};
pub use cost::{CalibrationCost, MAX_PCE_BASIS};
pub use identify::Refinement;
pub use metamodel::{CalibrationSummary, Metamodel, ModalBasis, ModeModel, StageSeconds, StaticResponse};
pub use parametrization::Parametrization;
