//! The wind on a three-dimensional building from one direction: the along-wind drag of
//! [`WindLoads`] on each floor's width facing the wind, and the wake's across-wind forces and
//! torques ([`aerodynamic`](super::aerodynamic)), both placed on every floor's three degrees of
//! freedom.
//!
//! The direction β is where the wind blows towards, counter-clockwise from the plan's x axis:
//! the drag acts along (cos β, sin β), the across-wind force along (−sin β, cos β), both at the
//! plan's centre, and the torque about it. The two parts are independent processes (the
//! buffeting drag and the wake are taken as uncorrelated, as the codes and force-balance studies
//! take them). The user's floor force records, when given, are the whole load instead: drag,
//! across-wind force and torque as measured together.

use super::aerodynamic::{Aerodynamics, WakeField, WakeGeometry};
use super::{FloorForces, StormGrid, WindLoads, WindSite, simulate};
use crate::error::{Error, Result};
use crate::structure::spatial::{DOFS_PER_FLOOR, SpatialStructure, plan_arms};
use crate::structure::storey_heights;
use crate::uncertainty::Rng;

/// The wind model of one three-dimensional building at one site.
#[derive(Debug, Clone)]
pub struct DirectionalWind {
    site: WindSite,
    /// Where the across-wind forces and torques come from; `None` for the drag alone.
    aerodynamics: Option<Aerodynamics>,
    heights: Vec<f64>,
    /// Each floor's plan extent along x and along y (m).
    extents: Vec<[f64; 2]>,
}

impl DirectionalWind {
    /// The wind on `structure` at `site`, with the wake loads of `aerodynamics` (`None`: the drag
    /// alone, as a plane study takes the wind).
    pub fn new(site: &WindSite, structure: &SpatialStructure, aerodynamics: Option<Aerodynamics>) -> Result<Self> {
        site.check()?;
        if let Some(Aerodynamics::Records(records)) = &aerodynamics
            && records.floors() != structure.floors()
        {
            return Err(Error::invalid(
                "wind-tunnel",
                format!(
                    "the floor force records load {} floors, the building has {}",
                    records.floors(),
                    structure.floors()
                ),
            ));
        }
        Ok(DirectionalWind {
            site: site.clone(),
            aerodynamics,
            heights: structure.floor_elevations.clone(),
            extents: structure.plans.iter().map(|p| [p.breadth, p.depth]).collect(),
        })
    }

    /// Where the loads beyond the drag come from (`None`: the drag alone).
    pub fn aerodynamics(&self) -> Option<&Aerodynamics> {
        self.aerodynamics.as_ref()
    }

    /// The drag's model for wind towards `direction_deg`: each floor's façade facing the wind is
    /// its plan's projection across the wind, |cos β|·depth + |sin β|·breadth.
    pub fn drag(&self, direction_deg: f64) -> Result<WindLoads> {
        let [cos, sin] = unit(direction_deg)?;
        let widths: Vec<f64> = self.extents.iter().map(|[b, d]| cos.abs() * d + sin.abs() * b).collect();
        WindLoads::on_floors(&self.site, &self.heights, &widths)
    }

    /// The wake's field at a station speed (m/s at 10 m) for wind towards `direction_deg`, or
    /// `None` for the drag alone. Its loads are those of the roof's plan.
    pub fn wake(&self, station_speed: f64, direction_deg: f64) -> Result<Option<WakeField>> {
        let Some(aerodynamics) = &self.aerodynamics else { return Ok(None) };
        WindLoads::check_speed(station_speed)?;
        let [breadth, depth] = self.extents[self.extents.len() - 1];
        let (loads, facing) = aerodynamics.at(direction_deg, breadth, depth)?;
        let roof = self.heights[self.heights.len() - 1];
        let storeys = storey_heights(&self.heights);
        let geometry = WakeGeometry {
            heights: &self.heights,
            storey_heights: &storeys,
            breadth: facing,
            roof_speed: self.site.mean_speed(roof, station_speed),
            air_density: self.site.air_density_kg_m3,
        };
        WakeField::new(&loads, geometry).map(Some)
    }

    /// One storm's loads on every degree of freedom (floor-major x, y, θ about each floor's centre
    /// of mass, at `centres_of_mass` from its plan's centre: a sample's eccentricity moves them):
    /// the drag's field, then the wake's, from `rng` in that order.
    pub fn floor_forces(
        &self,
        station_speed: f64,
        direction_deg: f64,
        centres_of_mass: &[[f64; 2]],
        storm: &StormGrid,
        rng: &mut Rng,
    ) -> Result<FloorForces> {
        let [cos, sin] = unit(direction_deg)?;
        if centres_of_mass.len() != self.heights.len() {
            return Err(Error::Internal(format!(
                "{} centres of mass for a building of {} floors",
                centres_of_mass.len(),
                self.heights.len()
            )));
        }
        if let Some(Aerodynamics::Records(records)) = &self.aerodynamics {
            WindLoads::check_speed(station_speed)?;
            let roof_speed = self.site.mean_speed(self.heights[self.heights.len() - 1], station_speed);
            let density = self.site.air_density_kg_m3;
            return records.floor_forces(direction_deg, roof_speed, density, centres_of_mass, storm, rng);
        }
        let drag = self.drag(direction_deg)?.floor_forces(station_speed, storm, rng)?;
        let mut forces = drag.on_plan([cos, sin], centres_of_mass);
        if let Some(field) = self.wake(station_speed, direction_deg)? {
            let n = self.heights.len();
            let grid = super::SpectralGrid { lines: self.site.frequencies, cutoff: self.site.cutoff_rad_s };
            let wake = simulate(&field, &grid, self.site.field_generation_step_s, storm, rng)?;
            for j in 0..n {
                let arms = plan_arms([-sin, cos], centres_of_mass[j]);
                for (d, arm) in arms.iter().enumerate() {
                    let series = &mut forces.series[DOFS_PER_FLOOR * j + d];
                    series.iter_mut().zip(&wake[j]).for_each(|(f, w)| *f += arm * w);
                }
                let torque = &mut forces.series[DOFS_PER_FLOOR * j + 2];
                torque.iter_mut().zip(&wake[n + j]).for_each(|(f, t)| *f += t);
            }
        }
        Ok(forces)
    }
}

/// (cos β, sin β) of a direction in degrees, exact on the axes.
fn unit(direction_deg: f64) -> Result<[f64; 2]> {
    if !direction_deg.is_finite() {
        return Err(Error::invalid("inputs.wind_direction", format!("must be finite, got {direction_deg}")));
    }
    Ok(crate::structure::spatial::plan_direction(direction_deg))
}
