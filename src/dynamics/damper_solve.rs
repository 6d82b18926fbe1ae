//! The implicit damper solve of a time step, in whichever unknowns converge faster.

use super::damper::{Dampers, ImplicitDamperSolve};
use super::dual::ForceDamperSolve;
use crate::error::Result;

/// Solves s = a − W Gᵀ F(G s) for the new velocities s and the damper forces F: in the forces where
/// that dual applies (one independent damper per unknown at most, α < 1: the full-order model),
/// because Newton converges there in a few iterations even where a damper comes to rest; otherwise
/// in the velocities (the reduced model, with more dampers than modes).
#[derive(Debug, Clone)]
pub enum DamperSolve {
    Velocities(ImplicitDamperSolve),
    Forces(ForceDamperSolve),
}

impl DamperSolve {
    pub fn new(w_inverse: Vec<f64>, map: Vec<Vec<(usize, f64)>>, dampers: &Dampers) -> Self {
        match ForceDamperSolve::new(&w_inverse, &map, dampers) {
            Some(forces) => DamperSolve::Forces(forces),
            None => DamperSolve::Velocities(ImplicitDamperSolve::new(w_inverse, map, dampers)),
        }
    }

    /// On entry `s` holds a guess of the new velocities and `forces` the previous step's forces
    /// (each formulation starts from its own); on exit both hold the solution. Returns the Newton
    /// iterations used.
    pub fn solve(&mut self, a: &[f64], s: &mut [f64], forces: &mut [f64]) -> Result<usize> {
        match self {
            DamperSolve::Velocities(solver) => solver.solve(a, s, forces),
            DamperSolve::Forces(solver) => solver.solve(a, s, forces),
        }
    }
}
