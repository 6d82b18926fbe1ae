//! A user-supplied lateral model: mass and stiffness matrices, floor geometry and a damper layout.

use super::{DamperPlacement, Structure};
use crate::error::{Error, Result};
use faer::Mat;
use serde::{Deserialize, Serialize};

/// A damper of a custom layout, in the terms a user writes down.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CustomDamper {
    /// Upper floor of the damper (1-based); it joins this floor to the one below (or the ground).
    pub floor: usize,
    /// Coefficient group (1-based): dampers of a group share the input `damper_c{group}`.
    pub group: usize,
    /// Cosine of the brace angle to the horizontal (1 for a horizontal damper).
    pub cos_angle: f64,
}

/// A custom structure as it arrives in a file or a request body.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CustomStructure {
    /// Mass matrix (kg), one row per floor from the ground up.
    pub mass: Vec<Vec<f64>>,
    /// Lateral stiffness matrix (N/m) at `reference_youngs_modulus`.
    pub stiffness: Vec<Vec<f64>>,
    /// Elevation of each floor (m).
    pub floor_elevations_m: Vec<f64>,
    /// Façade width of each floor exposed to the wind (m).
    pub floor_widths_m: Vec<f64>,
    /// The Young's modulus at which `stiffness` holds; the input `youngs_modulus` scales it.
    #[serde(default = "default_modulus")]
    pub reference_youngs_modulus: f64,
    #[serde(default)]
    pub dampers: Vec<CustomDamper>,
}

fn default_modulus() -> f64 {
    super::FRAME40_YOUNGS_MODULUS
}

fn to_matrix(field: &str, rows: &[Vec<f64>]) -> Result<Mat<f64>> {
    let n = rows.len();
    for (i, row) in rows.iter().enumerate() {
        if row.len() != n {
            return Err(Error::invalid(
                format!("{field}[{i}]"),
                format!("has {} entries but the matrix has {n} rows; it must be square", row.len()),
            ));
        }
    }
    Ok(Mat::from_fn(n, n, |i, j| rows[i][j]))
}

impl CustomStructure {
    pub fn build(&self) -> Result<Structure> {
        let stiffness = to_matrix("stiffness", &self.stiffness)?;
        let mass = to_matrix("mass", &self.mass)?;
        let floors = self.floor_elevations_m.len();
        let mut dampers = Vec::with_capacity(self.dampers.len());
        for (k, d) in self.dampers.iter().enumerate() {
            if d.floor == 0 || d.floor > floors {
                return Err(Error::invalid(format!("dampers[{k}].floor"), format!("must be between 1 and {floors}")));
            }
            if d.group == 0 {
                return Err(Error::invalid(format!("dampers[{k}].group"), "groups are numbered from 1"));
            }
            dampers.push(DamperPlacement {
                lower_floor: (d.floor - 1).checked_sub(1),
                upper_floor: d.floor - 1,
                cos_angle: d.cos_angle,
                group: d.group - 1,
            });
        }
        Structure::new(
            stiffness,
            mass,
            self.floor_elevations_m.clone(),
            self.floor_widths_m.clone(),
            self.reference_youngs_modulus,
            dampers,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_floors() -> CustomStructure {
        CustomStructure {
            mass: vec![vec![1e5, 0.0], vec![0.0, 1e5]],
            stiffness: vec![vec![4e8, -2e8], vec![-2e8, 2e8]],
            floor_elevations_m: vec![4.0, 8.0],
            floor_widths_m: vec![20.0, 20.0],
            reference_youngs_modulus: 2.1e11,
            dampers: vec![CustomDamper { floor: 1, group: 1, cos_angle: 0.8 }],
        }
    }

    #[test]
    fn valid_custom_structure_builds() {
        let s = two_floors().build().unwrap();
        assert_eq!(s.floors(), 2);
        assert_eq!(s.dampers[0].lower_floor, None);
    }

    #[test]
    fn bad_custom_structures_are_refused_with_the_field_named() {
        let mut c = two_floors();
        c.stiffness[0][1] = -1e8;
        assert!(c.build().unwrap_err().to_string().contains("symmetric"));
        let mut c = two_floors();
        c.stiffness = vec![vec![1e8, 2e8], vec![2e8, 1e8]];
        assert!(c.build().unwrap_err().to_string().starts_with("stiffness: must be positive definite"));
        let mut c = two_floors();
        c.mass[1][1] = -1.0;
        assert!(c.build().unwrap_err().to_string().starts_with("mass: must be positive definite"));
        let mut c = two_floors();
        c.mass[0][0] = f64::NAN;
        assert!(c.build().unwrap_err().to_string().starts_with("mass[0][0]"));
        let mut c = two_floors();
        c.floor_widths_m.pop();
        assert!(c.build().unwrap_err().to_string().starts_with("floor_widths_m"));
        let mut c = two_floors();
        c.stiffness[1].pop();
        assert!(c.build().unwrap_err().to_string().starts_with("stiffness[1]"));
        let mut c = two_floors();
        c.floor_elevations_m = vec![4.0, 3.0];
        assert!(c.build().unwrap_err().to_string().starts_with("floor_elevations_m[1]"));
        let mut c = two_floors();
        c.dampers[0].floor = 3;
        assert!(c.build().unwrap_err().to_string().starts_with("dampers[0].floor"));
    }
}
