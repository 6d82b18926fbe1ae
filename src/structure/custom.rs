//! A user-supplied lateral model: mass and stiffness matrices, floor geometry and a damper layout.

use super::{DamperPlacement, Structure};
use crate::error::{Error, Result};
use faer::Mat;
use serde::{Deserialize, Serialize};

/// Most floors of a custom structure: its eigen-analysis is dense (n³) and its full-order
/// reference integrates n degrees of freedom per step, so 200 keeps both well under a second per
/// study and a storm's full field (n series of the storm's length) within a few hundred MB; the
/// tallest buildings have about 160 storeys.
pub const MAX_FLOORS: usize = 200;
/// Most damper coefficient groups: each is one more uncertain input (`damper_c1` … `damper_c10`),
/// and the polynomial chaos bases grow with the number of inputs.
pub const MAX_DAMPER_GROUPS: usize = 10;
/// Most dampers of a layout: four per storey.
pub const MAX_DAMPERS: usize = 4 * MAX_FLOORS;

/// A damper of a custom layout, in the terms a user writes down.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct CustomDamper {
    /// Upper floor of the damper (1-based); it joins this floor to the one below (or the ground).
    #[cfg_attr(feature = "openapi", schema(minimum = 1, maximum = 200))]
    #[serde(deserialize_with = "crate::count::count")]
    pub floor: usize,
    /// Coefficient group (1-based): dampers of a group share the input `damper_c{group}`.
    #[cfg_attr(feature = "openapi", schema(minimum = 1, maximum = 10))]
    #[serde(deserialize_with = "crate::count::count")]
    pub group: usize,
    /// Cosine of the brace angle to the horizontal (1 for a horizontal damper).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1))]
    pub cos_angle: f64,
}

/// A custom structure as it arrives in a file or a request body.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct CustomStructure {
    /// Mass matrix (kg), one row per floor from the ground up; square, at most 200 floors.
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub mass: Vec<Vec<f64>>,
    /// Lateral stiffness matrix (N/m) at `reference_youngs_modulus`; square, as `mass`.
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub stiffness: Vec<Vec<f64>>,
    /// Elevation of each floor (m), increasing.
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub floor_elevations_m: Vec<f64>,
    /// Façade width of each floor exposed to the wind (m).
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub floor_widths_m: Vec<f64>,
    /// The Young's modulus at which `stiffness` holds; the input `youngs_modulus` scales it.
    #[serde(default = "default_modulus")]
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub reference_youngs_modulus: f64,
    /// The dampers, none by default; at most 800.
    #[serde(default)]
    #[cfg_attr(feature = "openapi", schema(max_items = 800))]
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
    /// Checks the matrices, the floor geometry and the dampers, and builds the [`Structure`].
    pub fn build(&self) -> Result<Structure> {
        for (field, count) in [
            ("mass", self.mass.len()),
            ("stiffness", self.stiffness.len()),
            ("floor_elevations_m", self.floor_elevations_m.len()),
            ("floor_widths_m", self.floor_widths_m.len()),
        ] {
            if count > MAX_FLOORS {
                return Err(Error::invalid(field, format!("at most {MAX_FLOORS} floors, got {count}")));
            }
        }
        if self.dampers.len() > MAX_DAMPERS {
            return Err(Error::invalid(
                "dampers",
                format!("at most {MAX_DAMPERS} dampers, got {}", self.dampers.len()),
            ));
        }
        let stiffness = to_matrix("stiffness", &self.stiffness)?;
        let mass = to_matrix("mass", &self.mass)?;
        let floors = self.floor_elevations_m.len();
        let mut dampers = Vec::with_capacity(self.dampers.len());
        for (k, d) in self.dampers.iter().enumerate() {
            if d.floor == 0 || d.floor > floors {
                return Err(Error::invalid(format!("dampers[{k}].floor"), format!("must be between 1 and {floors}")));
            }
            if d.group == 0 || d.group > MAX_DAMPER_GROUPS {
                return Err(Error::invalid(
                    format!("dampers[{k}].group"),
                    format!("groups are numbered from 1 to {MAX_DAMPER_GROUPS}, got {}", d.group),
                ));
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
        let mut c = two_floors();
        c.dampers[0].group = MAX_DAMPER_GROUPS + 1;
        assert!(c.build().unwrap_err().to_string().starts_with("dampers[0].group"));
        let mut c = two_floors();
        c.dampers[0].cos_angle = 0.0;
        assert!(c.build().unwrap_err().to_string().contains("cos_angle"));
        let mut c = two_floors();
        c.floor_elevations_m = (1..=MAX_FLOORS + 1).map(|j| j as f64).collect();
        assert!(c.build().unwrap_err().to_string().starts_with("floor_elevations_m: at most"));
    }
}
