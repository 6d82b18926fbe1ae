//! PC-NARX metamodels (sections 3.2-3.3): NARX dynamics per retained mode whose coefficients are
//! sparse polynomial-chaos expansions of the uncertain inputs.

pub mod batch;
mod calibrate;
mod cost;
mod design;
pub mod identify;
mod lanes;
pub mod lars;
mod metamodel;
pub mod narx;
mod options;
mod parametrization;
pub mod pce;
pub mod phases;
mod progress;
mod refine;

/// Proof that the processor has AVX-512F and FMA, for the loops compiled for it.
#[cfg(target_arch = "x86_64")]
pub(crate) use batch::Avx512Isa;
pub use batch::Workspace as BatchWorkspace;
pub use calibrate::calibrate;
pub use cost::{CalibrationCost, MAX_PCE_BASIS};
pub use design::{Design, design};
pub use lanes::LANES;
pub use lanes::Lanes;
pub use metamodel::{
    BatchInput, CalibrationSummary, Metamodel, ModalBasis, ModalScales, ModeDiagnostics, ModeModel, MotionSink,
    Reduction, StageSeconds, StaticResponse,
};
pub use options::{CalibrationOptions, MAX_EXPERIMENTS, WindCoverage};
pub use parametrization::Parametrization;
pub use progress::{Observer, Progress, Silent};
pub use refine::Refinement;
