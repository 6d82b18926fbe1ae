//! A user-supplied three-dimensional building, as it arrives in a file or a request body: either
//! storey by storey (mass, moment of inertia and the shear stiffness of the storey below in x, y
//! and torsion) or as mass and stiffness matrices over three degrees of freedom per floor, with
//! the floor plans and dampers placed on them. Every refusal names the field as the JSON spells it.

use super::DOFS_PER_FLOOR;
use super::{FloorPlan, PlanDamper, SpatialStructure, StoreyProperties, from_storeys, per_floor, plan_direction};
use crate::error::{Error, Result, require_finite, require_positive};
use crate::structure::DamperPlacement;
use crate::structure::custom::{MAX_DAMPER_GROUPS, MAX_DAMPERS, MAX_FLOORS};
use faer::Mat;
use serde::{Deserialize, Serialize};

/// Largest magnitude of a mass (kg), moment of inertia (kg·m²), stiffness (N/m, N·m/rad) or matrix
/// entry: six orders above the torsional stiffness of the stiffest towers (~10¹⁴ N·m/rad), and far
/// enough below `f64::MAX` that the assembly's sums and products stay finite.
const MAX_MAGNITUDE: f64 = 1e20;
/// Largest length on a plan or elevation (m): ten kilometres is beyond any building, and keeps the
/// squares of lengths (moments of inertia, torsional lever arms) exact enough.
const MAX_LENGTH_M: f64 = 1e4;
/// Largest damper direction in magnitude (degrees): a turn either way is every direction there is.
const MAX_DIRECTION_DEG: f64 = 360.0;

/// A floor's rectangular plan in the terms a user writes down: it sets where the centre of mass
/// and the dampers may sit, the default moment of inertia, and the corners occupants feel.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct CustomPlan {
    /// Breadth along the plan's x axis (m).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 10000))]
    pub breadth_m: f64,
    /// Depth along the plan's y axis (m).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 10000))]
    pub depth_m: f64,
}

/// One storey of a building given floor by floor: the floor's mass, and the storey below it as a
/// shear storey in x, y and torsion acting at the plan's centre (the centre of stiffness).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct CustomStorey {
    /// Elevation of the floor above the ground (m), increasing from storey to storey.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 10000))]
    pub elevation_m: f64,
    /// The floor's mass (kg), in both horizontal directions.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1e20))]
    pub mass_kg: f64,
    /// Moment of inertia about the vertical axis through the centre of mass (kg·m²); omitted, the
    /// floor's mass is taken as spread evenly over its plan, m (B² + D²)/12.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1e20))]
    pub moment_of_inertia_kg_m2: Option<f64>,
    /// Shear stiffness of the storey below along x (N/m), at `reference_youngs_modulus`.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1e20))]
    pub stiffness_x_n_per_m: f64,
    /// Shear stiffness of the storey below along y (N/m), at `reference_youngs_modulus`.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1e20))]
    pub stiffness_y_n_per_m: f64,
    /// Torsional stiffness of the storey below about the plan's centre (N·m/rad).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1e20))]
    pub torsional_stiffness_n_m_per_rad: f64,
    /// The floor's plan.
    pub plan: CustomPlan,
    /// The floor's centre of mass [x, y] from the plan's centre (m), [0, 0] by default; away from
    /// the centre of stiffness it couples sway with twist.
    #[serde(default)]
    pub centre_of_mass_m: [f64; 2],
}

/// A damper of a three-dimensional layout: its storey, group and brace angle as in a plane frame,
/// and the line on the plan it acts along, which decides how much sway and twist it resists.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct CustomPlanDamper {
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
    /// The damper's line on the plan, degrees counter-clockwise from the x axis (0 along x, 90
    /// along y, exactly).
    #[cfg_attr(feature = "openapi", schema(minimum = -360, maximum = 360))]
    pub direction_deg: f64,
    /// Where it sits on its upper floor's plan, [x, y] from the plan's centre (m).
    pub position_m: [f64; 2],
}

/// A custom three-dimensional building as it arrives in a file or a request body. Give either
/// `storeys`, or `mass` and `stiffness` with `floor_elevations_m` and `plans` (and optionally
/// `centres_of_mass_m`): the first is what a preliminary design knows, the second what a
/// finite-element model's condensation to rigid floors gives.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct CustomSpatialStructure {
    /// The storeys from the ground up; at most 200.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub storeys: Option<Vec<CustomStorey>>,
    /// Mass matrix (kg, kg·m²), one row per degree of freedom: floor by floor from the ground up,
    /// x, y, θ about the floor's centre of mass; square, three rows per floor.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(feature = "openapi", schema(min_items = 3, max_items = 600))]
    pub mass: Option<Vec<Vec<f64>>>,
    /// Stiffness matrix (N/m, N·m/rad, N/rad) at `reference_youngs_modulus`, ordered as `mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(feature = "openapi", schema(min_items = 3, max_items = 600))]
    pub stiffness: Option<Vec<Vec<f64>>>,
    /// With the matrices: the elevation of each floor (m), increasing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub floor_elevations_m: Option<Vec<f64>>,
    /// With the matrices: each floor's plan.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub plans: Option<Vec<CustomPlan>>,
    /// With the matrices: each floor's centre of mass [x, y] from its plan's centre (m), the origin
    /// of its degrees of freedom; all at the plan's centre by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[cfg_attr(feature = "openapi", schema(min_items = 1, max_items = 200))]
    pub centres_of_mass_m: Option<Vec<[f64; 2]>>,
    /// The Young's modulus at which the stiffness holds; the input `youngs_modulus` scales it.
    #[serde(default = "default_modulus")]
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1e20))]
    pub reference_youngs_modulus: f64,
    /// The dampers, none by default; at most 800.
    #[serde(default)]
    #[cfg_attr(feature = "openapi", schema(max_items = 800))]
    pub dampers: Vec<CustomPlanDamper>,
}

fn default_modulus() -> f64 {
    crate::structure::FRAME40_YOUNGS_MODULUS
}

impl CustomSpatialStructure {
    /// Checks the building (exactly one of its two forms, every number finite and within bounds,
    /// the dampers on their plans) and builds the [`SpatialStructure`].
    pub fn build(&self) -> Result<SpatialStructure> {
        let matrix_fields: Vec<&str> = [
            ("mass", self.mass.is_some()),
            ("stiffness", self.stiffness.is_some()),
            ("floor_elevations_m", self.floor_elevations_m.is_some()),
            ("plans", self.plans.is_some()),
            ("centres_of_mass_m", self.centres_of_mass_m.is_some()),
        ]
        .into_iter()
        .filter_map(|(field, given)| given.then_some(field))
        .collect();
        at_most("dampers", self.dampers.len(), MAX_DAMPERS, "dampers")?;
        magnitude("reference_youngs_modulus", self.reference_youngs_modulus)?;
        match &self.storeys {
            Some(_) if !matrix_fields.is_empty() => Err(Error::invalid(
                "storeys",
                format!(
                    "give either `storeys` or the matrices `mass` and `stiffness`, not both (`{}` given too)",
                    matrix_fields.join("`, `")
                ),
            )),
            Some(storeys) => self.build_storeys(storeys),
            None if matrix_fields.is_empty() => Err(Error::invalid(
                "storeys",
                "give either `storeys` or the matrices `mass` and `stiffness` with `floor_elevations_m` and `plans`",
            )),
            None => self.build_matrices(),
        }
    }

    fn build_storeys(&self, storeys: &[CustomStorey]) -> Result<SpatialStructure> {
        at_most("storeys", storeys.len(), MAX_FLOORS, "storeys")?;
        if storeys.is_empty() {
            return Err(Error::invalid("storeys", "at least one storey is needed"));
        }
        let mut below = 0.0;
        for (j, s) in storeys.iter().enumerate() {
            let field = |name: &str| format!("storeys[{j}].{name}");
            below = elevation(&field("elevation_m"), s.elevation_m, below)?;
            for (name, value) in [
                ("mass_kg", s.mass_kg),
                ("stiffness_x_n_per_m", s.stiffness_x_n_per_m),
                ("stiffness_y_n_per_m", s.stiffness_y_n_per_m),
                ("torsional_stiffness_n_m_per_rad", s.torsional_stiffness_n_m_per_rad),
            ] {
                magnitude(&field(name), value)?;
            }
            if let Some(inertia) = s.moment_of_inertia_kg_m2 {
                magnitude(&field("moment_of_inertia_kg_m2"), inertia)?;
            }
            let plan = floor_plan(&field("plan"), s.plan)?;
            on_plan(&field("centre_of_mass_m"), s.centre_of_mass_m, plan)?;
        }
        let plans: Vec<FloorPlan> = storeys.iter().map(|s| to_plan(s.plan)).collect();
        let dampers = self.plan_dampers(&plans)?;
        let properties: Vec<StoreyProperties> = storeys
            .iter()
            .map(|s| StoreyProperties {
                elevation: s.elevation_m,
                plan: to_plan(s.plan),
                mass: s.mass_kg,
                moment_of_inertia: s.moment_of_inertia_kg_m2,
                centre_of_mass: s.centre_of_mass_m,
                stiffness_x: s.stiffness_x_n_per_m,
                stiffness_y: s.stiffness_y_n_per_m,
                torsional_stiffness: s.torsional_stiffness_n_m_per_rad,
            })
            .collect();
        // What is left to fail is the assembled matrices' factorisation, which only the storeys
        // as a whole can answer for.
        from_storeys(&properties, self.reference_youngs_modulus, dampers).map_err(|e| match e {
            Error::Invalid { field, reason } if field.starts_with("stiffness") || field.starts_with("mass") => {
                Error::invalid("storeys", format!("the assembled {field}: {reason}"))
            }
            other => other,
        })
    }

    fn build_matrices(&self) -> Result<SpatialStructure> {
        let required = |field: &str| {
            Error::invalid(
                field,
                "is required with the matrix form (`mass`, `stiffness`, `floor_elevations_m`, `plans`)",
            )
        };
        let elevations = self.floor_elevations_m.as_deref().ok_or_else(|| required("floor_elevations_m"))?;
        let given_plans = self.plans.as_deref().ok_or_else(|| required("plans"))?;
        let mass_rows = self.mass.as_deref().ok_or_else(|| required("mass"))?;
        let stiffness_rows = self.stiffness.as_deref().ok_or_else(|| required("stiffness"))?;
        at_most("floor_elevations_m", elevations.len(), MAX_FLOORS, "floors")?;
        let floors = elevations.len();
        if floors == 0 {
            return Err(Error::invalid("floor_elevations_m", "at least one floor is needed"));
        }
        let mut below = 0.0;
        for (j, &z) in elevations.iter().enumerate() {
            below = elevation(&format!("floor_elevations_m[{j}]"), z, below)?;
        }
        per_floor("plans", given_plans.len(), floors)?;
        let centres = self.centres_of_mass_m.clone().unwrap_or_else(|| vec![[0.0; 2]; floors]);
        per_floor("centres_of_mass_m", centres.len(), floors)?;
        let mut plans = Vec::with_capacity(floors);
        for (j, (&plan, &centre)) in given_plans.iter().zip(&centres).enumerate() {
            let plan = floor_plan(&format!("plans[{j}]"), plan)?;
            on_plan(&format!("centres_of_mass_m[{j}]"), centre, plan)?;
            plans.push(plan);
        }
        let mass = to_matrix("mass", mass_rows, floors)?;
        let stiffness = to_matrix("stiffness", stiffness_rows, floors)?;
        let dampers = self.plan_dampers(&plans)?;
        SpatialStructure::new(
            stiffness,
            mass,
            elevations.to_vec(),
            plans,
            centres,
            self.reference_youngs_modulus,
            dampers,
        )
    }

    /// The dampers on `plans` (one per floor), each checked field by field.
    fn plan_dampers(&self, plans: &[FloorPlan]) -> Result<Vec<PlanDamper>> {
        let floors = plans.len();
        let mut dampers = Vec::with_capacity(self.dampers.len());
        for (k, d) in self.dampers.iter().enumerate() {
            let field = |name: &str| format!("dampers[{k}].{name}");
            if d.floor == 0 || d.floor > floors {
                return Err(Error::invalid(field("floor"), format!("must be between 1 and {floors}, got {}", d.floor)));
            }
            if d.group == 0 || d.group > MAX_DAMPER_GROUPS {
                return Err(Error::invalid(
                    field("group"),
                    format!("groups are numbered from 1 to {MAX_DAMPER_GROUPS}, got {}", d.group),
                ));
            }
            if !(d.cos_angle.is_finite() && d.cos_angle > 0.0 && d.cos_angle <= 1.0) {
                return Err(Error::invalid(field("cos_angle"), format!("must lie in (0, 1], got {}", d.cos_angle)));
            }
            if !(d.direction_deg.is_finite() && d.direction_deg.abs() <= MAX_DIRECTION_DEG) {
                return Err(Error::invalid(
                    field("direction_deg"),
                    format!("must lie within ±{MAX_DIRECTION_DEG}°, got {}", d.direction_deg),
                ));
            }
            on_plan(&field("position_m"), d.position_m, plans[d.floor - 1])?;
            dampers.push(PlanDamper {
                placement: DamperPlacement {
                    lower_floor: (d.floor - 1).checked_sub(1),
                    upper_floor: d.floor - 1,
                    cos_angle: d.cos_angle,
                    group: d.group - 1,
                },
                direction: plan_direction(d.direction_deg),
                position: d.position_m,
            });
        }
        Ok(dampers)
    }
}

fn to_plan(plan: CustomPlan) -> FloorPlan {
    FloorPlan { breadth: plan.breadth_m, depth: plan.depth_m }
}

/// Refuses more than `limit` entries, before anything is allocated for them.
fn at_most(field: &str, count: usize, limit: usize, what: &str) -> Result<()> {
    if count > limit {
        return Err(Error::invalid(field, format!("at most {limit} {what}, got {count}")));
    }
    Ok(())
}

/// A value that must be finite, positive and at most `max`.
fn bounded(field: &str, value: f64, max: f64) -> Result<f64> {
    require_positive(field, value)?;
    if value > max {
        return Err(Error::invalid(field, format!("must be at most {max:e}, got {value:e}")));
    }
    Ok(value)
}

/// A mass, moment of inertia, stiffness or modulus, at most [`MAX_MAGNITUDE`].
fn magnitude(field: &str, value: f64) -> Result<f64> {
    bounded(field, value, MAX_MAGNITUDE)
}

/// A length, at most [`MAX_LENGTH_M`].
fn length(field: &str, value: f64) -> Result<f64> {
    bounded(field, value, MAX_LENGTH_M)
}

/// A floor's elevation, above the one below (`below`, 0 for the ground); returns it.
fn elevation(field: &str, z: f64, below: f64) -> Result<f64> {
    length(field, z)?;
    if z <= below {
        return Err(Error::invalid(field, format!("elevations must be increasing, got {z} after {below}")));
    }
    Ok(z)
}

fn floor_plan(field: &str, plan: CustomPlan) -> Result<FloorPlan> {
    length(&format!("{field}.breadth_m"), plan.breadth_m)?;
    length(&format!("{field}.depth_m"), plan.depth_m)?;
    Ok(to_plan(plan))
}

/// A point that must lie on `plan` (or its edge), from the plan's centre.
fn on_plan(field: &str, point: [f64; 2], plan: FloorPlan) -> Result<()> {
    if !(point.iter().all(|p| p.is_finite()) && plan.holds(point)) {
        return Err(Error::invalid(
            field,
            format!("({}, {}) m lies outside the floor's {} × {} m plan", point[0], point[1], plan.breadth, plan.depth),
        ));
    }
    Ok(())
}

/// A matrix over the degrees of freedom of `floors` floors: at most 3·[`MAX_FLOORS`] rows, square,
/// three rows per floor, every entry finite and at most [`MAX_MAGNITUDE`] in magnitude.
fn to_matrix(field: &str, rows: &[Vec<f64>], floors: usize) -> Result<Mat<f64>> {
    let n = rows.len();
    at_most(field, n, DOFS_PER_FLOOR * MAX_FLOORS, "rows (three per floor)")?;
    for (i, row) in rows.iter().enumerate() {
        if row.len() != n {
            return Err(Error::invalid(
                format!("{field}[{i}]"),
                format!("has {} entries but the matrix has {n} rows; it must be square", row.len()),
            ));
        }
    }
    let size = DOFS_PER_FLOOR * floors;
    if n != size {
        return Err(Error::invalid(
            field,
            format!("has {n} rows but {floors} floors need {size}: three per floor (x, y, θ)"),
        ));
    }
    for (i, row) in rows.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            let entry = format!("{field}[{i}][{j}]");
            require_finite(&entry, v)?;
            if v.abs() > MAX_MAGNITUDE {
                return Err(Error::invalid(
                    entry,
                    format!("must be at most {MAX_MAGNITUDE:e} in magnitude, got {v:e}"),
                ));
            }
        }
    }
    Ok(Mat::from_fn(n, n, |i, j| rows[i][j]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::spatial::{Dof, SpatialModes, dof};

    const PLAN: CustomPlan = CustomPlan { breadth_m: 30.0, depth_m: 20.0 };
    const M: f64 = 2e5;
    const KX: f64 = 3e8;
    const KY: f64 = 2e8;
    const KT: f64 = 5e10;

    fn inertia() -> f64 {
        M * (30.0f64.powi(2) + 20.0f64.powi(2)) / 12.0
    }

    fn damper() -> CustomPlanDamper {
        CustomPlanDamper { floor: 1, group: 1, cos_angle: 0.8, direction_deg: 90.0, position_m: [15.0, 0.0] }
    }

    fn by_storeys(n: usize) -> CustomSpatialStructure {
        let storey = |j: usize| CustomStorey {
            elevation_m: 4.0 * (j + 1) as f64,
            mass_kg: M,
            moment_of_inertia_kg_m2: None,
            stiffness_x_n_per_m: KX,
            stiffness_y_n_per_m: KY,
            torsional_stiffness_n_m_per_rad: KT,
            plan: PLAN,
            centre_of_mass_m: [0.0, 0.0],
        };
        CustomSpatialStructure {
            storeys: Some((0..n).map(storey).collect()),
            mass: None,
            stiffness: None,
            floor_elevations_m: None,
            plans: None,
            centres_of_mass_m: None,
            reference_youngs_modulus: 2.1e11,
            dampers: vec![damper()],
        }
    }

    /// The same building as matrices: uncoupled shear buildings in x, y and θ, storey j joining
    /// floor j to floor j − 1 (the ground for j = 0), mass m, m, m (B² + D²)/12.
    fn by_matrices(n: usize) -> CustomSpatialStructure {
        let size = 3 * n;
        let (mut mass, mut stiffness) = (vec![vec![0.0; size]; size], vec![vec![0.0; size]; size]);
        for j in 0..n {
            for (d, k, m) in [(Dof::X, KX, M), (Dof::Y, KY, M), (Dof::Rotation, KT, inertia())] {
                let i = dof(j, d);
                mass[i][i] = m;
                stiffness[i][i] += k;
                if j > 0 {
                    let b = dof(j - 1, d);
                    stiffness[b][b] += k;
                    stiffness[i][b] -= k;
                    stiffness[b][i] -= k;
                }
            }
        }
        CustomSpatialStructure {
            storeys: None,
            mass: Some(mass),
            stiffness: Some(stiffness),
            floor_elevations_m: Some((1..=n).map(|j| 4.0 * j as f64).collect()),
            plans: Some(vec![PLAN; n]),
            centres_of_mass_m: None,
            ..by_storeys(0)
        }
    }

    #[test]
    fn identical_storeys_give_the_matrices_written_out() {
        let (a, b) = (by_storeys(3).build().unwrap(), by_matrices(3).build().unwrap());
        for (x, y) in [(&a.stiffness, &b.stiffness), (&a.mass, &b.mass)] {
            for i in 0..9 {
                for j in 0..9 {
                    assert!((x[(i, j)] - y[(i, j)]).abs() <= 1e-12 * y[(i, j)].abs(), "[{i}][{j}]");
                }
            }
        }
        assert_eq!((a.floor_elevations, a.plans, a.centres_of_mass), (b.floor_elevations, b.plans, b.centres_of_mass));
    }

    #[test]
    fn one_storey_sways_and_twists_at_the_closed_form_frequencies() {
        let modes = SpatialModes::all(&by_storeys(1).build().unwrap()).unwrap();
        let mut expected = [(KX / M).sqrt(), (KY / M).sqrt(), (KT / inertia()).sqrt()];
        expected.sort_by(f64::total_cmp);
        for (got, want) in modes.frequencies.iter().zip(expected) {
            assert!((got - want).abs() <= 1e-9 * want, "{got} against {want}");
        }
    }

    #[test]
    fn json_round_trips_and_defaults_apply() {
        let text = r#"{"storeys": [{"elevation_m": 4, "mass_kg": 2e5, "stiffness_x_n_per_m": 3e8,
            "stiffness_y_n_per_m": 2e8, "torsional_stiffness_n_m_per_rad": 5e10,
            "plan": {"breadth_m": 30, "depth_m": 20}}],
            "dampers": [{"floor": 1, "group": 1.0, "cos_angle": 0.8, "direction_deg": 90, "position_m": [15, 0]}]}"#;
        let c: CustomSpatialStructure = serde_json::from_str(text).unwrap();
        assert_eq!(c.reference_youngs_modulus, crate::structure::FRAME40_YOUNGS_MODULUS);
        assert_eq!(c.storeys.as_ref().unwrap()[0].centre_of_mass_m, [0.0, 0.0]);
        assert_eq!(c.build().unwrap().floors(), 1);
        for c in [c, by_matrices(2)] {
            let back: CustomSpatialStructure = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
            assert_eq!(back, c);
        }
        assert!(serde_json::from_str::<CustomSpatialStructure>(&text.replace("\"mass_kg\"", "\"mass\"")).is_err());
    }

    fn storey(c: &mut CustomSpatialStructure) -> &mut CustomStorey {
        &mut c.storeys.as_mut().unwrap()[1]
    }

    #[test]
    fn bad_buildings_are_refused_with_the_field_named() {
        type Edit = fn(&mut CustomSpatialStructure);
        let both = "storeys: give either `storeys` or the matrices `mass` and `stiffness`, not both (`mass` given";
        for (matrices, edit, field) in [
            (false, (|c| c.mass = by_matrices(2).mass) as Edit, both),
            (false, |c| c.storeys = None, "storeys: give either `storeys` or the matrices `mass` and `stiffness`"),
            (false, |c| *c = by_storeys(MAX_FLOORS + 1), "storeys: at most 200 storeys, got 201"),
            (true, |c| c.stiffness.as_mut().unwrap()[3].truncate(5), "stiffness[3]: has 5 entries"),
            (true, |c| c.mass = by_matrices(1).mass, "mass: has 3 rows but 2 floors need 6"),
            (true, |c| c.plans = None, "plans: is required"),
            (true, |c| c.stiffness.as_mut().unwrap()[0][0] = -1e300, "stiffness[0][0]: must be at most"),
            (true, |c| c.centres_of_mass_m = Some(vec![[0.0, 0.0], [0.0, 10.5]]), "centres_of_mass_m[1]: (0, 10.5)"),
            (false, |c| c.dampers[0].position_m = [15.5, 0.0], "dampers[0].position_m: (15.5, 0) m lies outside"),
            (false, |c| c.dampers[0].group = 0, "dampers[0].group:"),
            (false, |c| c.dampers[0].floor = 3, "dampers[0].floor:"),
            (false, |c| c.dampers[0].cos_angle = 1.5, "dampers[0].cos_angle:"),
            (false, |c| c.dampers[0].direction_deg = 1e300, "dampers[0].direction_deg:"),
            (false, |c| c.reference_youngs_modulus = 0.0, "reference_youngs_modulus:"),
            (false, |c| storey(c).mass_kg = 1e300, "storeys[1].mass_kg: must be at most"),
            (false, |c| storey(c).stiffness_x_n_per_m = -1.0, "storeys[1].stiffness_x_n_per_m:"),
            (false, |c| storey(c).torsional_stiffness_n_m_per_rad = 0.0, "storeys[1].torsional_stiffness_n_m_per_rad:"),
            (false, |c| storey(c).moment_of_inertia_kg_m2 = Some(-1.0), "storeys[1].moment_of_inertia_kg_m2:"),
            (false, |c| storey(c).elevation_m = 4.0, "storeys[1].elevation_m: elevations must be increasing"),
            (false, |c| storey(c).plan.depth_m = 1e9, "storeys[1].plan.depth_m:"),
            (false, |c| storey(c).centre_of_mass_m = [-16.0, 0.0], "storeys[1].centre_of_mass_m:"),
        ] {
            let mut c = if matrices { by_matrices(2) } else { by_storeys(2) };
            edit(&mut c);
            let refusal = c.build().unwrap_err().to_string();
            assert!(refusal.starts_with(field), "{refusal} for {field}");
        }
    }

    #[test]
    fn a_damper_along_y_acts_exactly_along_y() {
        let s = by_storeys(1).build().unwrap();
        assert_eq!(s.dampers[0].direction, [0.0, 1.0]);
        assert_eq!((s.dampers[0].placement.upper_floor, s.dampers[0].placement.lower_floor), (0, None));
        assert_eq!(s.dampers[0].weights([0.0, 0.0]), [0.0, 1.0, 15.0]);
    }
}
