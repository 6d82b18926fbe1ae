//! The damped building in time: nonlinear viscous dampers and the two reference integrators,
//! reduced-order (retained modes) and full-order (every floor).

mod damper;
mod damper_map;
mod factored;
mod full;
mod modal;
mod modal_lanes;
mod motion;
mod power;
#[cfg(test)]
mod spatial_checks;
#[cfg(test)]
mod spatial_random_vibration;

pub use damper::{Dampers, ImplicitDamperSolve};
pub use full::{FloorResponse, FullSystem, integrate_full};
pub use modal::{ModalResponse, integrate_reduced};
pub use modal_lanes::{ReducedStorm, integrate_reduced_lanes};
pub use motion::{ModalMotion, SampleModel};
pub use power::{power, power_lanes, sign_power};
