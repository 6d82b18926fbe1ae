//! The responses of a three-dimensional building, as requests name them: a floor's displacement,
//! drift and acceleration (peak or RMS) along x, along y or in twist, and the resultant horizontal
//! acceleration at the floor's worst corner (peak or RMS), the quantity comfort criteria judge.
//! Written like a plane frame's response, `{"kind": "acceleration", "floor": 40, "direction": "y"}`,
//! `{"kind": "corner_acceleration", "floor": 40}`.

use crate::error::{Error, Result};
use crate::structure::spatial::{Dof, SpatialStructure, corner_acceleration, corner_history, dof};
use crate::study::SpatialRun;
use crate::wind::rms_stride;
use serde::{Deserialize, Serialize};

/// What is read off a floor of a three-dimensional building.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum SpatialKind {
    /// Displacement at the floor's centre of mass along a direction (m), or its twist (rad).
    Displacement,
    /// Inter-storey drift at the centre of mass along x or y (m).
    Drift,
    /// Acceleration at the centre of mass along a direction (m/s²), or in twist (rad/s²).
    Acceleration,
    /// Root mean square of that acceleration over the storm.
    RmsAcceleration,
    /// Peak resultant horizontal acceleration at the floor's worst corner (m/s²).
    CornerAcceleration,
    /// Largest RMS resultant horizontal acceleration among the floor's corners (m/s²).
    RmsCornerAcceleration,
}

impl SpatialKind {
    /// Every kind, in the order tables list them.
    pub const ALL: [SpatialKind; 6] = [
        SpatialKind::Displacement,
        SpatialKind::Drift,
        SpatialKind::Acceleration,
        SpatialKind::RmsAcceleration,
        SpatialKind::CornerAcceleration,
        SpatialKind::RmsCornerAcceleration,
    ];

    /// The name requests and answers use.
    pub fn name(self) -> &'static str {
        match self {
            SpatialKind::Displacement => "displacement",
            SpatialKind::Drift => "drift",
            SpatialKind::Acceleration => "acceleration",
            SpatialKind::RmsAcceleration => "rms_acceleration",
            SpatialKind::CornerAcceleration => "corner_acceleration",
            SpatialKind::RmsCornerAcceleration => "rms_corner_acceleration",
        }
    }

    /// The kind named `name` (a dash standing for an underscore, as on a command line).
    pub fn parse(name: &str) -> Result<SpatialKind> {
        let spelled = name.replace('-', "_");
        SpatialKind::ALL.into_iter().find(|kind| kind.name() == spelled).ok_or_else(|| {
            let names: Vec<&str> = SpatialKind::ALL.iter().map(|k| k.name()).collect();
            Error::invalid(
                "response",
                format!(
                    "`{name}` is not a response of a three-dimensional building; its responses are {}",
                    names.join(", ")
                ),
            )
        })
    }

    /// Whether the kind is read at the floor's corners (and so takes no direction).
    pub fn at_corners(self) -> bool {
        matches!(self, SpatialKind::CornerAcceleration | SpatialKind::RmsCornerAcceleration)
    }

    /// Whether one storm gives the RMS rather than the peak.
    pub fn is_rms(self) -> bool {
        matches!(self, SpatialKind::RmsAcceleration | SpatialKind::RmsCornerAcceleration)
    }
}

/// A response of a three-dimensional building: a kind at a floor, along a direction for the kinds
/// read at the centre of mass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct SpatialResponse {
    /// The response's kind.
    pub kind: SpatialKind,
    /// Floor (1-based).
    pub floor: usize,
    /// `x`, `y` or `rotation` for the responses at the centre of mass; absent at the corners.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<Dof>,
}

impl SpatialResponse {
    /// The response a request names: its kind at `floor` (the roof when absent) along `direction`,
    /// checked against `structure`.
    pub fn located(
        kind: SpatialKind,
        floor: Option<usize>,
        direction: Option<Dof>,
        structure: &SpatialStructure,
    ) -> Result<Self> {
        let response = SpatialResponse { kind, floor: floor.unwrap_or(structure.floors()), direction };
        response.check(structure)?;
        Ok(response)
    }

    /// The floor lies in the building; the centre-of-mass kinds have a direction (drift along x or
    /// y only), the corner kinds none.
    pub fn check(&self, structure: &SpatialStructure) -> Result<()> {
        let floors = structure.floors();
        if self.floor == 0 || self.floor > floors {
            return Err(Error::invalid("floor", format!("must be between 1 and {floors}, got {}", self.floor)));
        }
        match (self.kind.at_corners(), self.direction) {
            (true, Some(_)) => Err(Error::invalid(
                "direction",
                format!("{} is the resultant of both directions and the twist; give no direction", self.kind.name()),
            )),
            (false, None) => Err(Error::invalid(
                "direction",
                format!("{} of a three-dimensional building is along x, y or rotation; give one", self.kind.name()),
            )),
            (false, Some(Dof::Rotation)) if self.kind == SpatialKind::Drift => {
                Err(Error::invalid("direction", "a drift is along x or y"))
            }
            _ => Ok(()),
        }
    }

    /// The SI unit of the response's values.
    pub fn unit(&self) -> &'static str {
        match (self.kind, self.direction) {
            (SpatialKind::Displacement | SpatialKind::Drift, Some(Dof::Rotation)) => "rad",
            (SpatialKind::Displacement | SpatialKind::Drift, _) => "m",
            (SpatialKind::Acceleration | SpatialKind::RmsAcceleration, Some(Dof::Rotation)) => "rad/s²",
            _ => "m/s²",
        }
    }

    /// A human name, for tables and axes.
    pub fn describe(&self) -> String {
        let floor = self.floor;
        let along = match self.direction {
            Some(Dof::X) => " along x",
            Some(Dof::Y) => " along y",
            _ => "",
        };
        match (self.kind, self.direction) {
            (SpatialKind::Displacement, Some(Dof::Rotation)) => format!("rotation of floor {floor}"),
            (SpatialKind::Acceleration, Some(Dof::Rotation)) => format!("rotational acceleration of floor {floor}"),
            (SpatialKind::RmsAcceleration, Some(Dof::Rotation)) => {
                format!("RMS rotational acceleration of floor {floor}")
            }
            (SpatialKind::Displacement, _) => format!("displacement of floor {floor}{along}"),
            (SpatialKind::Drift, _) => format!("drift below floor {floor}{along}"),
            (SpatialKind::Acceleration, _) => format!("acceleration of floor {floor}{along}"),
            (SpatialKind::RmsAcceleration, _) => format!("RMS acceleration of floor {floor}{along}"),
            (SpatialKind::CornerAcceleration, _) => format!("corner acceleration of floor {floor}"),
            (SpatialKind::RmsCornerAcceleration, _) => format!("RMS corner acceleration of floor {floor}"),
        }
    }

    /// Its column in a table of histories: kind, floor, direction and unit, e.g.
    /// `displacement_40_rotation_rad`, `corner_acceleration_40_m_s2`.
    pub fn column(&self) -> String {
        let unit = match self.unit() {
            "m/s²" => "m_s2",
            "rad/s²" => "rad_s2",
            other => other,
        };
        let direction = match self.direction {
            Some(Dof::X) => "_x",
            Some(Dof::Y) => "_y",
            Some(Dof::Rotation) => "_rotation",
            None => "",
        };
        format!("{}_{}{direction}_{unit}", self.kind.name(), self.floor)
    }

    /// What one storm gives of it, for titles: "peak …", or an RMS as it is.
    pub fn per_storm(&self) -> String {
        if self.kind.is_rms() { self.describe() } else { format!("peak {}", self.describe()) }
    }

    /// The one value per storm: the peak absolute value, or the RMS over steps 0.1 s apart
    /// ([`rms_stride`]) as for a plane frame's floor; at the corners, the worst corner's.
    pub fn of_run(&self, run: &SpatialRun, structure: &SpatialStructure, time_step: f64) -> Result<f64> {
        self.check(structure)?;
        let j = self.floor - 1;
        let stride = rms_stride(time_step);
        if self.kind.at_corners() {
            let [x, y, rotation] = [Dof::X, Dof::Y, Dof::Rotation].map(|d| run.accelerations[dof(j, d)].as_slice());
            let worst = corner_acceleration(&structure.plans[j], run.centres_of_mass[j], x, y, rotation, stride);
            return Ok(if self.kind.is_rms() { worst.rms } else { worst.peak });
        }
        let history = self.history(run, structure)?;
        Ok(if self.kind.is_rms() {
            let sampled = history.iter().step_by(stride);
            let count = sampled.clone().count().max(1);
            (sampled.map(|a| a * a).sum::<f64>() / count as f64).sqrt()
        } else {
            history.iter().fold(0.0, |m, v| m.max(v.abs()))
        })
    }

    /// The response's history in a storm (for an RMS, the history whose RMS it is); at the corners
    /// the resultant at the corner of the largest peak.
    pub fn history(&self, run: &SpatialRun, structure: &SpatialStructure) -> Result<Vec<f64>> {
        self.check(structure)?;
        let j = self.floor - 1;
        let Some(direction) = self.direction else {
            let [x, y, rotation] = [Dof::X, Dof::Y, Dof::Rotation].map(|d| run.accelerations[dof(j, d)].as_slice());
            let plan = &structure.plans[j];
            let worst = corner_acceleration(plan, run.centres_of_mass[j], x, y, rotation, 1);
            return Ok(corner_history(plan, run.centres_of_mass[j], [x, y, rotation], worst.peak_corner));
        };
        let at = |floor: usize| run.displacements[dof(floor, direction)].as_slice();
        Ok(match self.kind {
            SpatialKind::Displacement => at(j).to_vec(),
            SpatialKind::Drift if j == 0 => at(0).to_vec(),
            SpatialKind::Drift => at(j).iter().zip(at(j - 1)).map(|(u, l)| u - l).collect(),
            _ => run.accelerations[dof(j, direction)].clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::spatial::frame40_3d;
    use serde_json::json;

    fn response(kind: &str, floor: Option<usize>, direction: Option<Dof>) -> Result<SpatialResponse> {
        let building = frame40_3d([0.0, 0.0]).unwrap();
        SpatialResponse::located(SpatialKind::parse(kind)?, floor, direction, &building)
    }

    /// Requests write a response as kind, floor and direction and read back what answers write;
    /// the roof by default; every wrong combination is refused naming its field.
    #[test]
    fn responses_are_named_by_kind_floor_and_direction() {
        let roof_y = response("acceleration", None, Some(Dof::Y)).unwrap();
        assert_eq!(roof_y.floor, 40);
        let written = json!({"kind": "acceleration", "floor": 40, "direction": "y"});
        assert_eq!(serde_json::to_value(roof_y).unwrap(), written);
        assert_eq!(serde_json::from_value::<SpatialResponse>(written).unwrap(), roof_y);
        let corner = response("corner-acceleration", Some(12), None).unwrap();
        assert_eq!(serde_json::to_value(corner).unwrap(), json!({"kind": "corner_acceleration", "floor": 12}));
        assert_eq!(response("displacement", None, Some(Dof::Rotation)).unwrap().unit(), "rad");
        let field = |r: Result<SpatialResponse>| r.unwrap_err().to_string().split(':').next().unwrap().to_string();
        assert_eq!(field(response("damper_force", None, Some(Dof::X))), "response");
        assert_eq!(field(response("displacement", None, None)), "direction");
        assert_eq!(field(response("corner_acceleration", None, Some(Dof::X))), "direction");
        assert_eq!(field(response("drift", None, Some(Dof::Rotation))), "direction");
        assert_eq!(field(response("drift", Some(41), Some(Dof::X))), "floor");
        assert!(serde_json::from_value::<SpatialResponse>(json!({"kind": "drift", "floor": 1, "group": 2})).is_err());
    }

    /// On a made-up run whose floors move by known sines, each response's value is its closed form:
    /// peaks and RMS at the centre of mass, the drift as the difference of two floors, and at the
    /// corners the sway plus the twist times the corner's arm.
    #[test]
    fn values_are_read_off_a_run_as_their_closed_forms() {
        let building = frame40_3d([0.0, 0.0]).unwrap();
        let (dt, steps) = (0.01, 20_001);
        let omega = 2.0 * std::f64::consts::PI * 0.25;
        let sine =
            |amplitude: f64| -> Vec<f64> { (0..steps).map(|t| amplitude * (omega * t as f64 * dt).sin()).collect() };
        let mut displacements = vec![vec![0.0; steps]; building.dofs()];
        let mut accelerations = vec![vec![0.0; steps]; building.dofs()];
        for j in 0..building.floors() {
            let share = (j + 1) as f64 / 40.0;
            displacements[dof(j, Dof::X)] = sine(0.2 * share);
            displacements[dof(j, Dof::Y)] = sine(0.1 * share);
            accelerations[dof(j, Dof::Y)] = sine(0.05 * share);
            accelerations[dof(j, Dof::Rotation)] = sine(0.001 * share);
        }
        let run = SpatialRun { displacements, accelerations, direction: 0.0, centres_of_mass: vec![[0.0, 0.0]; 40] };
        let value = |kind: &str, floor: usize, direction: Option<Dof>| {
            response(kind, Some(floor), direction).unwrap().of_run(&run, &building, dt).unwrap()
        };
        let close = |a: f64, b: f64| assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-12), "{a} against {b}");
        close(value("displacement", 40, Some(Dof::X)), 0.2);
        close(value("drift", 40, Some(Dof::X)), 0.2 / 40.0);
        close(value("drift", 1, Some(Dof::Y)), 0.1 / 40.0);
        close(value("acceleration", 20, Some(Dof::Y)), 0.025);
        // Sampled every 0.1 s, 2 001 samples: 50 whole periods of 40 (Σ sin² = 1 000) and one zero.
        let rms_factor = (1000.0f64 / 2001.0).sqrt();
        close(value("rms_acceleration", 40, Some(Dof::Y)), 0.05 * rms_factor);
        // The corner (12.2, ±12.2) m moves along y by 0.05 + 12.2·0.001 and along x by ∓12.2·0.001,
        // in phase.
        let corner = (0.05f64 + 12.2 * 0.001).hypot(12.2 * 0.001);
        close(value("corner_acceleration", 40, None), corner);
        close(value("rms_corner_acceleration", 40, None), corner * rms_factor);
        let history = response("corner_acceleration", Some(40), None).unwrap().history(&run, &building).unwrap();
        close(history.iter().fold(0.0, |m: f64, v| m.max(*v)), corner);
    }
}
