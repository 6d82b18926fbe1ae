//! The building: lateral mass and stiffness matrices with one degree of freedom per floor, the floor
//! geometry the wind acts on, and where the dampers sit.
//!
//! A [`Structure`] is always valid once built: square symmetric matrices of the same size, a positive
//! definite stiffness and mass, increasing floor elevations. Everything downstream relies on that.

mod custom;
mod frame;
mod modes;
mod presets;
mod sections;
pub mod spatial;

pub use custom::{CustomStructure, MAX_DAMPER_GROUPS, MAX_FLOORS};
pub use frame::{FrameSpec, StoreySections};
pub use modes::Modes;
pub use presets::{FRAME40_YOUNGS_MODULUS, frame40};
pub use sections::Section;

use crate::error::{Error, Result, require_finite, require_positive};
use faer::{Mat, Side};

/// A damper between two consecutive floors (or the ground and the first floor).
#[derive(Debug, Clone, PartialEq)]
pub struct DamperPlacement {
    /// Floor index (0-based) of the lower end; `None` is the ground.
    pub lower_floor: Option<usize>,
    /// Floor index (0-based) of the upper end.
    pub upper_floor: usize,
    /// Cosine of the brace angle to the horizontal: axial velocity = cos θ · relative floor velocity.
    pub cos_angle: f64,
    /// Coefficient group (0-based); every damper of a group shares one uncertain coefficient.
    pub group: usize,
}

/// The lateral model of a building, one degree of freedom per floor, floors numbered from the ground up.
#[derive(Debug, Clone)]
pub struct Structure {
    /// Lateral stiffness (N/m) at [`Structure::reference_youngs_modulus`]; an uncertain Young's
    /// modulus scales it linearly.
    pub stiffness: Mat<f64>,
    /// Mass matrix (kg) at mass factor 1.
    pub mass: Mat<f64>,
    /// Elevation of each floor above the ground (m).
    pub floor_elevations: Vec<f64>,
    /// Width of the façade each floor exposes to the wind (m).
    pub floor_widths: Vec<f64>,
    /// The Young's modulus (Pa) at which `stiffness` was assembled.
    pub reference_youngs_modulus: f64,
    /// The damper layout; may be empty.
    pub dampers: Vec<DamperPlacement>,
}

impl Structure {
    /// Checks every invariant and builds the structure; errors name the offending field.
    pub fn new(
        stiffness: Mat<f64>,
        mass: Mat<f64>,
        floor_elevations: Vec<f64>,
        floor_widths: Vec<f64>,
        reference_youngs_modulus: f64,
        dampers: Vec<DamperPlacement>,
    ) -> Result<Self> {
        let n = floor_elevations.len();
        if n == 0 {
            return Err(Error::invalid("floor_elevations_m", "at least one floor is needed"));
        }
        check_square_symmetric("stiffness", &stiffness, n)?;
        check_square_symmetric("mass", &mass, n)?;
        check_positive_definite("stiffness", &stiffness)?;
        check_positive_definite("mass", &mass)?;
        check_elevations(&floor_elevations)?;
        if floor_widths.len() != n {
            return Err(Error::invalid(
                "floor_widths_m",
                format!("has {} entries but there are {n} floors", floor_widths.len()),
            ));
        }
        for (j, &w) in floor_widths.iter().enumerate() {
            require_positive(&format!("floor_widths_m[{j}]"), w)?;
        }
        require_positive("reference_youngs_modulus", reference_youngs_modulus)?;
        check_dampers(&dampers, n)?;
        Ok(Structure { stiffness, mass, floor_elevations, floor_widths, reference_youngs_modulus, dampers })
    }

    /// Number of floors: the lateral degrees of freedom.
    pub fn floors(&self) -> usize {
        self.floor_elevations.len()
    }

    /// Height of the storey below each floor (m): the floor's share of the façade in the paper's
    /// quasi-steady model (A_j = h_j W).
    pub fn storey_heights(&self) -> Vec<f64> {
        storey_heights(&self.floor_elevations)
    }

    /// Number of damper coefficient groups (one uncertain coefficient each).
    pub fn damper_groups(&self) -> usize {
        self.dampers.iter().map(|d| d.group + 1).max().unwrap_or(0)
    }
}

/// Floor elevations must be finite, positive and increasing.
fn check_elevations(floor_elevations: &[f64]) -> Result<()> {
    let mut below = 0.0;
    for (j, &z) in floor_elevations.iter().enumerate() {
        require_finite(&format!("floor_elevations_m[{j}]"), z)?;
        if z <= below {
            return Err(Error::invalid(
                format!("floor_elevations_m[{j}]"),
                format!("elevations must be positive and increasing, got {z} after {below}"),
            ));
        }
        below = z;
    }
    Ok(())
}

fn check_square_symmetric(field: &str, a: &Mat<f64>, n: usize) -> Result<()> {
    if a.nrows() != n || a.ncols() != n {
        return Err(Error::invalid(
            field,
            format!("must be {n}×{n} (one row per degree of freedom), got {}×{}", a.nrows(), a.ncols()),
        ));
    }
    let mut scale: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let v = a[(i, j)];
            if !v.is_finite() {
                return Err(Error::invalid(format!("{field}[{i}][{j}]"), format!("must be finite, got {v}")));
            }
            scale = scale.max(v.abs());
        }
    }
    for i in 0..n {
        for j in 0..i {
            if (a[(i, j)] - a[(j, i)]).abs() > 1e-9 * scale {
                return Err(Error::invalid(
                    field,
                    format!("must be symmetric: entry [{i}][{j}] = {} but [{j}][{i}] = {}", a[(i, j)], a[(j, i)]),
                ));
            }
        }
    }
    Ok(())
}

fn check_positive_definite(field: &str, a: &Mat<f64>) -> Result<()> {
    if a.llt(Side::Lower).is_err() {
        return Err(Error::invalid(field, "must be positive definite (its Cholesky factorisation failed)"));
    }
    Ok(())
}

fn check_dampers(dampers: &[DamperPlacement], floors: usize) -> Result<()> {
    for (k, d) in dampers.iter().enumerate() {
        let field = format!("dampers[{k}]");
        if d.upper_floor >= floors {
            return Err(Error::invalid(field, format!("floor {} does not exist ({floors} floors)", d.upper_floor + 1)));
        }
        if let Some(lower) = d.lower_floor
            && lower + 1 != d.upper_floor
        {
            return Err(Error::invalid(field, "a damper must join two consecutive floors"));
        }
        if d.lower_floor.is_none() && d.upper_floor != 0 {
            return Err(Error::invalid(field, "only the first floor's damper may start at the ground"));
        }
        if !(d.cos_angle.is_finite() && d.cos_angle > 0.0 && d.cos_angle <= 1.0) {
            return Err(Error::invalid(field, format!("cos_angle must lie in (0, 1], got {}", d.cos_angle)));
        }
    }
    let groups = dampers.iter().map(|d| d.group + 1).max().unwrap_or(0);
    for g in 0..groups {
        if !dampers.iter().any(|d| d.group == g) {
            return Err(Error::invalid(
                "dampers",
                format!("group {} has no damper; groups must be numbered 1..G without gaps", g + 1),
            ));
        }
    }
    Ok(())
}

/// The storey each floor carries, from the floor below it (the ground for the first): z_j − z_{j−1}.
pub fn storey_heights(elevations: &[f64]) -> Vec<f64> {
    let mut below = 0.0;
    elevations
        .iter()
        .map(|&z| {
            let h = z - below;
            below = z;
            h
        })
        .collect()
}
