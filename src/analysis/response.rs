//! The physical responses a user asks about, from a sample's modal motion. Displacements, drifts
//! and damper strokes are fixed combinations of the modal displacements (u = Φ y, Eq. 5);
//! accelerations and damper forces follow from the equations of motion ([`crate::dynamics::SampleModel`]).

use crate::dynamics::{ModalMotion, SampleModel};
use crate::error::{Error, Result};
use crate::structure::Structure;
use crate::wind::ModalForces;
use serde::{Deserialize, Serialize};
use std::cell::OnceCell;

/// Standard gravity (m/s²), for accelerations in milli-g.
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// A response history of the building.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Response {
    /// Displacement of a floor (1-based; the roof is the top floor), m.
    Displacement { floor: usize },
    /// Inter-storey drift u_floor − u_{floor−1} (the ground does not move), m.
    Drift { floor: usize },
    /// Floor acceleration (the ground does not move, so relative and absolute agree), m/s².
    Acceleration { floor: usize },
    /// Axial force of the damper in the storey below the floor, N.
    DamperForce { floor: usize },
    /// Axial elongation of that damper's brace from the unloaded frame, cos θ·(u_floor − u_{floor−1}), m.
    DamperStroke { floor: usize },
}

/// A response's kind, as requests name it.
pub const RESPONSE_KINDS: [&str; 5] = ["displacement", "drift", "acceleration", "damper_force", "damper_stroke"];

impl Response {
    /// The response of kind `kind` (one of [`RESPONSE_KINDS`]) at `floor`.
    pub fn of_kind(kind: &str, floor: usize) -> Result<Response> {
        Ok(match kind {
            "displacement" => Response::Displacement { floor },
            "drift" => Response::Drift { floor },
            "acceleration" => Response::Acceleration { floor },
            "damper_force" => Response::DamperForce { floor },
            "damper_stroke" => Response::DamperStroke { floor },
            other => {
                return Err(Error::invalid(
                    "response",
                    format!("unknown response `{other}`; the responses are {}", RESPONSE_KINDS.join(", ")),
                ));
            }
        })
    }

    pub fn floor(&self) -> usize {
        match *self {
            Response::Displacement { floor }
            | Response::Drift { floor }
            | Response::Acceleration { floor }
            | Response::DamperForce { floor }
            | Response::DamperStroke { floor } => floor,
        }
    }

    pub fn kind(&self) -> &'static str {
        match self {
            Response::Displacement { .. } => "displacement",
            Response::Drift { .. } => "drift",
            Response::Acceleration { .. } => "acceleration",
            Response::DamperForce { .. } => "damper_force",
            Response::DamperStroke { .. } => "damper_stroke",
        }
    }

    /// The SI unit of the response's values.
    pub fn unit(&self) -> &'static str {
        match self {
            Response::Acceleration { .. } => "m/s²",
            Response::DamperForce { .. } => "N",
            _ => "m",
        }
    }

    /// The unit as a suffix of a column name: `m`, `m_s2` or `n`.
    pub fn unit_tag(&self) -> &'static str {
        match self {
            Response::Acceleration { .. } => "m_s2",
            Response::DamperForce { .. } => "n",
            _ => "m",
        }
    }

    /// A human name, for tables and axes.
    pub fn describe(&self) -> String {
        match *self {
            Response::Displacement { floor } => format!("displacement of floor {floor}"),
            Response::Drift { floor } => format!("drift below floor {floor}"),
            Response::Acceleration { floor } => format!("acceleration of floor {floor}"),
            Response::DamperForce { floor } => format!("force of the damper below floor {floor}"),
            Response::DamperStroke { floor } => format!("stroke of the damper below floor {floor}"),
        }
    }

    /// Checks the floor, and for a damper response that the storey has a damper.
    pub fn check(&self, structure: &Structure) -> Result<()> {
        let (floor, floors) = (self.floor(), structure.floors());
        if floor == 0 || floor > floors {
            return Err(Error::invalid("floor", format!("must be between 1 and {floors}, got {floor}")));
        }
        if matches!(self, Response::DamperForce { .. } | Response::DamperStroke { .. }) {
            damper_below(structure, floor)?;
        }
        Ok(())
    }

    /// The response as Σ_m w_m y_m where it is one (displacement, drift, stroke): the weight of each
    /// mode, from shapes `shapes[m][floor]`. `None` for the responses that need the equations of motion.
    pub fn modal_weights(&self, shapes: &[Vec<f64>], structure: &Structure) -> Result<Option<Vec<f64>>> {
        self.check(structure)?;
        let weight = |floor: usize| -> Vec<f64> { shapes.iter().map(|s| s[floor - 1]).collect() };
        let storey = |floor: usize| -> Vec<f64> {
            if floor == 1 {
                weight(1)
            } else {
                weight(floor).iter().zip(weight(floor - 1)).map(|(a, b)| a - b).collect()
            }
        };
        Ok(match *self {
            Response::Displacement { floor } => Some(weight(floor)),
            Response::Drift { floor } => Some(storey(floor)),
            Response::DamperStroke { floor } => {
                let cos = structure.dampers[damper_below(structure, floor)?].cos_angle;
                Some(storey(floor).iter().map(|w| cos * w).collect())
            }
            Response::Acceleration { .. } | Response::DamperForce { .. } => None,
        })
    }

    /// The response's history in a sample's motion.
    pub fn history(&self, view: &ResponseView) -> Result<Vec<f64>> {
        let combine = |modal: &[Vec<f64>], weights: &[f64]| -> Vec<f64> {
            let steps = modal.first().map_or(0, Vec::len);
            (0..steps).map(|t| modal.iter().zip(weights).map(|(y, w)| w * y[t]).sum()).collect()
        };
        if let Some(weights) = self.modal_weights(view.shapes, view.structure)? {
            return Ok(combine(&view.motion.displacements, &weights));
        }
        Ok(match *self {
            Response::Acceleration { floor } => {
                let weights: Vec<f64> = view.shapes.iter().map(|s| s[floor - 1]).collect();
                combine(view.modal_accelerations(), &weights)
            }
            Response::DamperForce { floor } => {
                view.model.damper_force(damper_below(view.structure, floor)?, view.motion)
            }
            _ => unreachable!("the linear responses returned above"),
        })
    }

    /// Peak absolute value over the storm.
    pub fn peak(&self, view: &ResponseView) -> Result<f64> {
        if let Response::DamperForce { floor } = *self {
            self.check(view.structure)?;
            return Ok(view.model.damper_force_peak(damper_below(view.structure, floor)?, view.motion));
        }
        Ok(self.history(view)?.iter().fold(0.0, |m, v| m.max(v.abs())))
    }
}

/// The index of the damper in the storey below `floor` (1-based).
pub(super) fn damper_below(structure: &Structure, floor: usize) -> Result<usize> {
    structure
        .dampers
        .iter()
        .position(|d| d.upper_floor + 1 == floor)
        .ok_or_else(|| Error::invalid("floor", format!("the storey below floor {floor} has no damper")))
}

/// What a response is read from: one sample's motion, its reduced model and its loads. The modal
/// accelerations are computed once, when a response first needs them.
pub struct ResponseView<'a> {
    pub shapes: &'a [Vec<f64>],
    pub structure: &'a Structure,
    pub motion: &'a ModalMotion,
    pub model: &'a SampleModel<'a>,
    pub forces: &'a ModalForces,
    accelerations: OnceCell<Vec<Vec<f64>>>,
}

impl<'a> ResponseView<'a> {
    pub fn new(
        shapes: &'a [Vec<f64>],
        structure: &'a Structure,
        motion: &'a ModalMotion,
        model: &'a SampleModel<'a>,
        forces: &'a ModalForces,
    ) -> Self {
        ResponseView { shapes, structure, motion, model, forces, accelerations: OnceCell::new() }
    }

    fn modal_accelerations(&self) -> &[Vec<f64>] {
        self.accelerations.get_or_init(|| self.model.modal_accelerations(self.motion, self.forces))
    }
}
