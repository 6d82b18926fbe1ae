//! The physical responses a user asks about, from a sample's modal motion. Displacements, drifts
//! and damper strokes are fixed combinations of the modal displacements (u = Φ y, Eq. 5);
//! accelerations and damper forces follow from the equations of motion ([`crate::dynamics::SampleModel`]).

use crate::dynamics::{ModalMotion, SampleModel};
use crate::error::{Error, Result};
use crate::structure::Structure;
use crate::wind::ModalForces;
pub use crate::wind::rms_stride;
use serde::{Deserialize, Serialize};
use std::cell::OnceCell;

/// Standard gravity (m/s²), for accelerations in milli-g.
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// A response history of the building: of one floor, or for the dampers the envelope of a
/// coefficient group (at every instant the largest magnitude among its dampers, so its peak is the
/// largest of their peaks: what devices made alike are designed for).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(into = "ResponseName", try_from = "ResponseName")]
pub enum Response {
    /// Displacement of a floor (1-based; the roof is the top floor), m.
    Displacement {
        /// The floor (1-based).
        floor: usize,
    },
    /// Inter-storey drift u_floor − u_{floor−1} (the ground does not move), m.
    Drift {
        /// The floor above the storey (1-based).
        floor: usize,
    },
    /// Floor acceleration (the ground does not move, so relative and absolute agree), m/s².
    Acceleration {
        /// The floor (1-based).
        floor: usize,
    },
    /// Root mean square of a floor's acceleration over the storm, m/s²: the quantity of
    /// ISO 6897-type comfort criteria. Its "peak" (the one value per storm) is the RMS.
    RmsAcceleration {
        /// The floor (1-based).
        floor: usize,
    },
    /// Axial force of the damper in the storey below the floor, N.
    DamperForce {
        /// The floor above the damper (1-based).
        floor: usize,
    },
    /// Axial elongation of that damper's brace from the unloaded frame, cos θ·(u_floor − u_{floor−1}), m.
    DamperStroke {
        /// The floor above the damper (1-based).
        floor: usize,
    },
    /// The largest axial force among the dampers of a group (1-based), N.
    GroupDamperForce {
        /// The damper coefficient group (1-based).
        group: usize,
    },
    /// The largest brace elongation among the dampers of a group (1-based), m.
    GroupDamperStroke {
        /// The damper coefficient group (1-based).
        group: usize,
    },
}

/// A response's kind, as requests and answers name it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum ResponseKind {
    /// Floor displacement (m).
    #[default]
    Displacement,
    /// Inter-storey drift below the floor (m).
    Drift,
    /// Floor acceleration (m/s²), from the equations of motion of the reduced model.
    Acceleration,
    /// Root mean square of the floor acceleration over the storm (m/s²).
    RmsAcceleration,
    /// Axial force of the damper in the storey below the floor, or the largest of a group's (N).
    DamperForce,
    /// Axial elongation of that damper's brace, or the largest of a group's (m).
    DamperStroke,
}

impl ResponseKind {
    /// Every kind, in the order tables list them.
    pub const ALL: [ResponseKind; 6] = [
        ResponseKind::Displacement,
        ResponseKind::Drift,
        ResponseKind::Acceleration,
        ResponseKind::RmsAcceleration,
        ResponseKind::DamperForce,
        ResponseKind::DamperStroke,
    ];

    /// The name requests and answers use.
    pub fn name(self) -> &'static str {
        match self {
            ResponseKind::Displacement => "displacement",
            ResponseKind::Drift => "drift",
            ResponseKind::Acceleration => "acceleration",
            ResponseKind::RmsAcceleration => "rms_acceleration",
            ResponseKind::DamperForce => "damper_force",
            ResponseKind::DamperStroke => "damper_stroke",
        }
    }

    /// The kind named `name` (a dash standing for an underscore, as on a command line).
    pub fn parse(name: &str) -> Result<ResponseKind> {
        let spelled = name.replace('-', "_");
        ResponseKind::ALL.into_iter().find(|kind| kind.name() == spelled).ok_or_else(|| {
            let names: Vec<&str> = ResponseKind::ALL.iter().map(|k| k.name()).collect();
            Error::invalid("response", format!("unknown response `{name}`; the responses are {}", names.join(", ")))
        })
    }

    /// The response of this kind at `floor`.
    pub fn at_floor(self, floor: usize) -> Response {
        match self {
            ResponseKind::Displacement => Response::Displacement { floor },
            ResponseKind::Drift => Response::Drift { floor },
            ResponseKind::Acceleration => Response::Acceleration { floor },
            ResponseKind::RmsAcceleration => Response::RmsAcceleration { floor },
            ResponseKind::DamperForce => Response::DamperForce { floor },
            ResponseKind::DamperStroke => Response::DamperStroke { floor },
        }
    }

    /// The envelope of this kind over the dampers of `group` (1-based): damper responses only.
    pub fn of_group(self, group: usize) -> Result<Response> {
        match self {
            ResponseKind::DamperForce => Ok(Response::GroupDamperForce { group }),
            ResponseKind::DamperStroke => Ok(Response::GroupDamperStroke { group }),
            _ => Err(Error::invalid("group", "only damper_force and damper_stroke are taken over a damper group")),
        }
    }

    /// The response a request names: at `floor` (the roof when absent) or over a damper `group`,
    /// checked against `structure`.
    pub fn located(self, floor: Option<usize>, group: Option<usize>, structure: &Structure) -> Result<Response> {
        let response = match (floor, group) {
            (Some(_), Some(_)) => return Err(Error::invalid("group", "give a floor or a damper group, not both")),
            (_, Some(group)) => self.of_group(group)?,
            (floor, None) => self.at_floor(floor.unwrap_or(structure.floors())),
        };
        response.check(structure)?;
        Ok(response)
    }
}

/// How requests and answers write a response: its kind at a floor, or over a damper group.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct ResponseName {
    /// The response's kind.
    pub kind: ResponseKind,
    /// Floor (1-based); absent for a damper group's envelope.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<usize>,
    /// Damper group (1-based) whose largest response this is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<usize>,
}

impl From<Response> for ResponseName {
    fn from(response: Response) -> ResponseName {
        let (floor, group) = match response {
            Response::GroupDamperForce { group } | Response::GroupDamperStroke { group } => (None, Some(group)),
            other => (other.floor(), None),
        };
        ResponseName { kind: response.kind(), floor, group }
    }
}

impl TryFrom<ResponseName> for Response {
    type Error = String;

    fn try_from(name: ResponseName) -> std::result::Result<Response, String> {
        match (name.floor, name.group) {
            (Some(floor), None) => Ok(name.kind.at_floor(floor)),
            (None, Some(group)) => name.kind.of_group(group).map_err(|e| e.to_string()),
            _ => Err("a response names exactly one of `floor` and `group`".into()),
        }
    }
}

impl Response {
    /// The floor of a floor's response; `None` for a group's envelope.
    pub fn floor(&self) -> Option<usize> {
        match *self {
            Response::Displacement { floor }
            | Response::Drift { floor }
            | Response::Acceleration { floor }
            | Response::RmsAcceleration { floor }
            | Response::DamperForce { floor }
            | Response::DamperStroke { floor } => Some(floor),
            Response::GroupDamperForce { .. } | Response::GroupDamperStroke { .. } => None,
        }
    }

    /// The response's kind, as requests name it (a group's envelope has its dampers' kind).
    pub fn kind(&self) -> ResponseKind {
        match self {
            Response::Displacement { .. } => ResponseKind::Displacement,
            Response::Drift { .. } => ResponseKind::Drift,
            Response::Acceleration { .. } => ResponseKind::Acceleration,
            Response::RmsAcceleration { .. } => ResponseKind::RmsAcceleration,
            Response::DamperForce { .. } | Response::GroupDamperForce { .. } => ResponseKind::DamperForce,
            Response::DamperStroke { .. } | Response::GroupDamperStroke { .. } => ResponseKind::DamperStroke,
        }
    }

    /// The floor responses whose largest peak this is: the group's dampers for an envelope, the
    /// response itself otherwise.
    pub fn members(&self, structure: &Structure) -> Result<Vec<Response>> {
        self.check(structure)?;
        let below =
            |group: usize| structure.dampers.iter().filter(move |d| d.group + 1 == group).map(|d| d.upper_floor + 1);
        Ok(match *self {
            Response::GroupDamperForce { group } => below(group).map(|floor| Response::DamperForce { floor }).collect(),
            Response::GroupDamperStroke { group } => {
                below(group).map(|floor| Response::DamperStroke { floor }).collect()
            }
            other => vec![other],
        })
    }

    /// The SI unit of the response's values.
    pub fn unit(&self) -> &'static str {
        match self {
            Response::Acceleration { .. } | Response::RmsAcceleration { .. } => "m/s²",
            Response::DamperForce { .. } | Response::GroupDamperForce { .. } => "N",
            _ => "m",
        }
    }

    /// The unit as a suffix of a column name: `m`, `m_s2` or `n`.
    pub fn unit_tag(&self) -> &'static str {
        match self {
            Response::Acceleration { .. } | Response::RmsAcceleration { .. } => "m_s2",
            Response::DamperForce { .. } | Response::GroupDamperForce { .. } => "n",
            _ => "m",
        }
    }

    /// A human name, for tables and axes.
    pub fn describe(&self) -> String {
        match *self {
            Response::Displacement { floor } => format!("displacement of floor {floor}"),
            Response::Drift { floor } => format!("drift below floor {floor}"),
            Response::Acceleration { floor } => format!("acceleration of floor {floor}"),
            Response::RmsAcceleration { floor } => format!("RMS acceleration of floor {floor}"),
            Response::DamperForce { floor } => format!("force of the damper below floor {floor}"),
            Response::DamperStroke { floor } => format!("stroke of the damper below floor {floor}"),
            Response::GroupDamperForce { group } => format!("largest force among the dampers of group {group}"),
            Response::GroupDamperStroke { group } => format!("largest stroke among the dampers of group {group}"),
        }
    }

    /// What one storm gives of it, for titles: "peak …", or the RMS acceleration as it is.
    pub fn per_storm(&self) -> String {
        match self {
            Response::RmsAcceleration { .. } => self.describe(),
            _ => format!("peak {}", self.describe()),
        }
    }

    /// Checks the floor, for a damper response that the storey has a damper, for a group's
    /// envelope that the group exists.
    pub fn check(&self, structure: &Structure) -> Result<()> {
        let floor = match *self {
            Response::GroupDamperForce { group } | Response::GroupDamperStroke { group } => {
                let groups = structure.damper_groups();
                if group == 0 || group > groups {
                    let range = match groups {
                        0 => "the structure has no dampers".to_string(),
                        _ => format!("must be between 1 and {groups}"),
                    };
                    return Err(Error::invalid("group", format!("{range}, got {group}")));
                }
                return Ok(());
            }
            Response::Displacement { floor }
            | Response::Drift { floor }
            | Response::Acceleration { floor }
            | Response::RmsAcceleration { floor }
            | Response::DamperForce { floor }
            | Response::DamperStroke { floor } => floor,
        };
        let floors = structure.floors();
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
            _ => None,
        })
    }

    /// Whether this response is a floor's acceleration, peak or RMS: from the equations of motion.
    pub fn is_acceleration(&self) -> bool {
        matches!(self, Response::Acceleration { .. } | Response::RmsAcceleration { .. })
    }

    /// The one value per storm of this response's `history` of steps of `time_step` (s): for an
    /// RMS acceleration the RMS of the steps 0.1 s apart (to the nearest whole step: `rms_stride`)
    /// from the first, otherwise the peak absolute value.
    pub fn of_history(&self, history: &[f64], time_step: f64) -> f64 {
        match self {
            Response::RmsAcceleration { .. } => {
                let sampled = history.iter().step_by(rms_stride(time_step));
                let count = sampled.clone().count().max(1);
                (sampled.map(|a| a * a).sum::<f64>() / count as f64).sqrt()
            }
            _ => history.iter().fold(0.0, |m, v| m.max(v.abs())),
        }
    }

    /// The response's history in a sample's motion (for an RMS acceleration, the acceleration
    /// whose RMS it is); a group's envelope is, step by step, the largest magnitude among its
    /// dampers.
    pub fn history(&self, view: &ResponseView) -> Result<Vec<f64>> {
        let combine = |modal: &[Vec<f64>], weights: &[f64]| -> Vec<f64> {
            let steps = modal.first().map_or(0, Vec::len);
            (0..steps).map(|t| modal.iter().zip(weights).map(|(y, w)| w * y[t]).sum()).collect()
        };
        if let Some(weights) = self.modal_weights(view.shapes, view.structure)? {
            return Ok(combine(&view.motion.displacements, &weights));
        }
        Ok(match *self {
            Response::Acceleration { floor } | Response::RmsAcceleration { floor } => {
                let weights: Vec<f64> = view.shapes.iter().map(|s| s[floor - 1]).collect();
                combine(view.modal_accelerations(), &weights)
            }
            Response::DamperForce { floor } => {
                view.model.damper_force(damper_below(view.structure, floor)?, view.motion)
            }
            group => envelope(group.members(view.structure)?.iter().map(|m| m.history(view)))?,
        })
    }

    /// Peak absolute value over the storm (the RMS for an RMS acceleration).
    pub fn peak(&self, view: &ResponseView) -> Result<f64> {
        match *self {
            Response::DamperForce { floor } => {
                self.check(view.structure)?;
                Ok(view.model.damper_force_peak(damper_below(view.structure, floor)?, view.motion))
            }
            Response::GroupDamperForce { .. } | Response::GroupDamperStroke { .. } => {
                self.members(view.structure)?.iter().try_fold(0.0, |m: f64, r| Ok(m.max(r.peak(view)?)))
            }
            _ => Ok(self.of_history(&self.history(view)?, view.time_step)),
        }
    }
}

/// Step by step the largest magnitude among `histories`.
pub(super) fn envelope(histories: impl Iterator<Item = Result<Vec<f64>>>) -> Result<Vec<f64>> {
    let mut largest: Vec<f64> = Vec::new();
    for history in histories {
        let history = history?;
        largest.resize(history.len(), 0.0);
        for (l, v) in largest.iter_mut().zip(history) {
            *l = l.max(v.abs());
        }
    }
    Ok(largest)
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
    /// The mode shapes: `shapes[m][f]` is mode m's component at floor f + 1.
    pub shapes: &'a [Vec<f64>],
    /// The structure the floors and dampers belong to.
    pub structure: &'a Structure,
    /// The sample's modal displacements and velocities.
    pub motion: &'a ModalMotion,
    /// The sample's reduced model (modes, damping, dampers), for the equations of motion.
    pub model: &'a SampleModel<'a>,
    /// The storm's modal forces on the motion's time grid.
    pub forces: &'a ModalForces,
    /// The storm's time step (s).
    pub time_step: f64,
    accelerations: OnceCell<Vec<Vec<f64>>>,
}

impl<'a> ResponseView<'a> {
    /// A view of one sample's motion; the modal accelerations are computed on first use.
    pub fn new(
        shapes: &'a [Vec<f64>],
        structure: &'a Structure,
        motion: &'a ModalMotion,
        model: &'a SampleModel<'a>,
        forces: &'a ModalForces,
        time_step: f64,
    ) -> Self {
        ResponseView { shapes, structure, motion, model, forces, time_step, accelerations: OnceCell::new() }
    }

    fn modal_accelerations(&self) -> &[Vec<f64>] {
        self.accelerations.get_or_init(|| self.model.modal_accelerations(self.motion, self.forces))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::frame40;
    use serde_json::json;

    /// Answers write a floor's response and a group's envelope under the same kind names, and read
    /// back what they wrote; a name with both or neither location is refused.
    #[test]
    fn responses_are_named_by_kind_and_location() {
        for (response, written) in [
            (Response::Drift { floor: 12 }, json!({"kind": "drift", "floor": 12})),
            (Response::GroupDamperForce { group: 3 }, json!({"kind": "damper_force", "group": 3})),
            (Response::DamperStroke { floor: 7 }, json!({"kind": "damper_stroke", "floor": 7})),
        ] {
            assert_eq!(serde_json::to_value(response).unwrap(), written);
            assert_eq!(serde_json::from_value::<Response>(written).unwrap(), response);
        }
        for wrong in [
            json!({"kind": "drift", "floor": 1, "group": 1}),
            json!({"kind": "drift"}),
            json!({"kind": "acceleration", "group": 1}),
        ] {
            assert!(serde_json::from_value::<Response>(wrong.clone()).is_err(), "{wrong}");
        }
    }

    /// A request's kind, floor and group resolve to the roof by default, and every wrong
    /// combination is refused naming the field.
    #[test]
    fn requests_locate_their_response() {
        let structure = frame40().unwrap();
        let at = |kind: &str, floor, group| ResponseKind::parse(kind).and_then(|k| k.located(floor, group, &structure));
        assert_eq!(at("acceleration", None, None).unwrap(), Response::Acceleration { floor: 40 });
        assert_eq!(at("damper_stroke", None, Some(4)).unwrap(), Response::GroupDamperStroke { group: 4 });
        let field = |result: Result<Response>| result.unwrap_err().to_string().split(':').next().unwrap().to_string();
        assert_eq!(field(at("velocity", None, None)), "response");
        assert_eq!(field(at("drift", None, Some(1))), "group");
        assert_eq!(field(at("damper_force", Some(3), Some(1))), "group");
        assert_eq!(field(at("damper_force", None, Some(5))), "group");
        assert_eq!(field(at("displacement", Some(41), None)), "floor");
        assert_eq!(Response::GroupDamperForce { group: 1 }.members(&structure).unwrap().len(), 10);
    }
}
