//! Stochastic wind loads (section 4.2 and Appendix 1): the mean speed profile, the Kaimal-type
//! spectrum with Davenport coherence, Deodatis' spectral-representation simulation, quasi-steady
//! floor forces and modal forces — either projected from the full floor field or simulated directly
//! from the projected cross-spectral matrix Φᵀ S_f Φ (the fast path, equal in law).

pub mod aerodynamic;
mod directional;
mod histories;
mod loads;
mod modal;
mod site;
mod spectral;
mod spectrum;
mod transform;

pub use directional::DirectionalWind;
pub use histories::{CoarseModalForces, FloorForces, ForceSource, ModalForces};
pub use loads::WindLoads;
pub use modal::ModalWind;
pub use site::{RMS_SAMPLING_INTERVAL_S, StormGrid, WindSite, rms_stride};
pub use spectral::{CoarseSeries, CrossSpectralDensity, CubicSchedule, SpectralGrid, simulate, simulate_coarse};
pub use spectrum::{FieldSpectrum, Projected, ProjectedSpectrum};
pub use transform::TransformWorkspace;
