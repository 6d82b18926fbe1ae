//! Stochastic wind loads (section 4.2 and Appendix 1): the mean speed profile, the Kaimal-type
//! spectrum with Davenport coherence, Deodatis' spectral-representation simulation, quasi-steady
//! floor forces and modal forces — either projected from the full floor field or simulated directly
//! from the projected cross-spectral matrix Φᵀ S_f Φ (the fast path, equal in law).

mod forces;
mod modal;
mod pruned;
mod site;
mod source;
mod spectral;
mod spectrum;

pub use forces::{FloorForces, ModalForces, WindLoads};
pub use modal::{CoarseModalForces, ModalWind};
pub use pruned::Workspace;
pub use site::{StormGrid, WindSite};
pub use source::ForceSource;
pub use spectral::{CoarseSeries, CrossSpectralDensity, CubicSchedule, SpectralGrid, simulate, simulate_coarse};
pub use spectrum::{FieldSpectrum, ProjectedSpectrum};
