//! The physical responses a user asks about, from modal histories: u = Φ y (Eq. 5).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// A response history of the building.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Response {
    /// Displacement of a floor (1-based; the roof is the top floor), m.
    Displacement { floor: usize },
    /// Inter-storey drift u_floor − u_{floor−1} (the ground does not move), m.
    Drift { floor: usize },
}

impl Response {
    pub fn floor(&self) -> usize {
        match *self {
            Response::Displacement { floor } | Response::Drift { floor } => floor,
        }
    }

    pub fn check(&self, floors: usize) -> Result<()> {
        let floor = self.floor();
        if floor == 0 || floor > floors {
            return Err(Error::invalid("floor", format!("must be between 1 and {floors}, got {floor}")));
        }
        Ok(())
    }

    /// The response as Σ_m w_m y_m: the weight of each mode, from shapes `shapes[m][floor]`.
    pub fn weights(&self, shapes: &[Vec<f64>]) -> Vec<f64> {
        let weight = |floor: usize| -> Vec<f64> { shapes.iter().map(|s| s[floor - 1]).collect() };
        match *self {
            Response::Displacement { floor } => weight(floor),
            Response::Drift { floor: 1 } => weight(1),
            Response::Drift { floor } => weight(floor).iter().zip(weight(floor - 1)).map(|(a, b)| a - b).collect(),
        }
    }

    /// The history from modal displacements `modal[m][t]` and shapes `shapes[m][floor]`.
    pub fn history(&self, shapes: &[Vec<f64>], modal: &[Vec<f64>]) -> Vec<f64> {
        let weights = self.weights(shapes);
        let steps = modal.first().map_or(0, Vec::len);
        (0..steps).map(|t| modal.iter().zip(&weights).map(|(y, w)| w * y[t]).sum()).collect()
    }

    /// Peak absolute value of the history.
    pub fn peak(&self, shapes: &[Vec<f64>], modal: &[Vec<f64>]) -> f64 {
        self.history(shapes, modal).iter().fold(0.0, |m, v| m.max(v.abs()))
    }
}
