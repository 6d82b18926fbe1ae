//! The damped building in time: nonlinear viscous dampers and the two reference integrators,
//! reduced-order (retained modes) and full-order (every floor).

mod damper;
mod damper_solve;
mod dual;
mod factored;
mod full;
mod modal;

pub use damper::{Dampers, ImplicitDamperSolve};
pub use damper_solve::DamperSolve;
pub use dual::ForceDamperSolve;
pub use full::{FloorResponse, FullSystem, integrate_full};
pub use modal::{ModalResponse, integrate_reduced};
