//! The wind model of one building at one site: quasi-steady floor forces (Eq. 14, linearised),
//! simulated as a full field on every floor or projected on the modes before interpolation.

use super::histories::{CoarseModalForces, FloorForces};
use super::spectral::{CoarseSeries, SpectralGrid, simulate, simulate_coarse};
use super::spectrum::FieldSpectrum;
use super::{StormGrid, TransformWorkspace, WindSite};
use crate::error::{Error, Result};
use crate::structure::{Structure, storey_heights};
use crate::uncertainty::Rng;
use faer::MatRef;

/// The wind model of one building at one site.
#[derive(Debug, Clone)]
pub struct WindLoads {
    /// The site's parameters: everything about the wind that is not uncertain.
    pub site: WindSite,
    /// Floor elevations z_j (m).
    pub heights: Vec<f64>,
    /// η_j = ½ ρ C̄ A_j with A_j = h_j W_j (kg/m): f_j = η_j (v̄_j² + 2 v̄_j v_j).
    pub exposure: Vec<f64>,
}

impl WindLoads {
    /// The wind model of `structure` at `site`; its lowest floor must lie above the site's
    /// roughness length.
    pub fn new(site: &WindSite, structure: &Structure) -> Result<Self> {
        Self::on_floors(site, &structure.floor_elevations, &structure.floor_widths)
    }

    /// The wind model of floors at `elevations` (m, increasing from the ground) whose façades
    /// facing the wind are `widths` wide (m), each carrying the storey below it.
    pub fn on_floors(site: &WindSite, elevations: &[f64], widths: &[f64]) -> Result<Self> {
        site.check()?;
        if elevations.first().is_none_or(|&z| z <= site.site_roughness_m) {
            return Err(Error::invalid(
                "floor_elevations_m[0]",
                "the lowest floor must lie above the site's roughness length for the log profile to hold",
            ));
        }
        let half_rho_c = 0.5 * site.air_density_kg_m3 * site.pressure_coefficient;
        let exposure = storey_heights(elevations).iter().zip(widths).map(|(h, w)| half_rho_c * h * w).collect();
        Ok(WindLoads { site: site.clone(), heights: elevations.to_vec(), exposure })
    }

    /// The cross-spectral density of the floors' speed fluctuations at a station speed (m/s).
    pub fn spectrum(&self, wind_speed: f64) -> FieldSpectrum {
        FieldSpectrum::new(&self.site, &self.heights, wind_speed)
    }

    /// The site's frequency discretisation.
    pub fn grid(&self) -> SpectralGrid {
        SpectralGrid { lines: self.site.frequencies, cutoff: self.site.cutoff_rad_s }
    }

    /// The station speeds the wind model serves.
    pub fn check_speed(wind_speed: f64) -> Result<()> {
        if wind_speed.is_finite() && wind_speed > 0.0 && wind_speed < 150.0 {
            Ok(())
        } else {
            Err(Error::invalid("inputs.wind_speed", format!("must lie in (0, 150) m/s, got {wind_speed}")))
        }
    }

    /// Mean floor forces η_j v̄_j² (N) at a station speed, v̄_j from Eq. (13) as in the spectrum.
    pub fn mean_forces(&self, wind_speed: f64) -> Vec<f64> {
        self.exposure
            .iter()
            .zip(&self.heights)
            .map(|(e, &z)| {
                let v = self.site.mean_speed(z, wind_speed);
                e * v * v
            })
            .collect()
    }

    /// The full field: the fluctuating speed at every floor, then the quasi-steady forces.
    pub fn floor_forces(&self, wind_speed: f64, storm: &StormGrid, rng: &mut Rng) -> Result<FloorForces> {
        Self::check_speed(wind_speed)?;
        let spectrum = self.spectrum(wind_speed);
        let speeds = simulate(&spectrum, &self.grid(), self.site.field_generation_step_s, storm, rng)?;
        let mean = self.mean_forces(wind_speed);
        let series = speeds
            .iter()
            .enumerate()
            .map(|(j, v)| {
                let gain = 2.0 * self.exposure[j] * spectrum.mean_speeds[j];
                v.iter().map(|x| mean[j] + gain * x).collect()
            })
            .collect();
        Ok(FloorForces { mean, series })
    }

    /// The full field projected on the modes before it is interpolated to a storm's grid: equal to
    /// projecting the interpolated floor forces (the interpolation is linear), for a tenth of the work.
    pub fn projected_field(
        &self,
        wind_speed: f64,
        shapes: MatRef<'_, f64>,
        duration: f64,
        workspace: &mut TransformWorkspace,
        rng: &mut Rng,
    ) -> Result<CoarseModalForces> {
        Self::check_speed(wind_speed)?;
        let spectrum = self.spectrum(wind_speed);
        let speeds =
            simulate_coarse(&spectrum, &self.grid(), self.site.field_generation_step_s, duration, workspace, rng)?;
        let floor_means = self.mean_forces(wind_speed);
        let modes = shapes.ncols();
        let mut mean = vec![0.0; modes];
        let mut series = vec![vec![0.0; speeds.series[0].len()]; modes];
        for (j, v) in speeds.series.iter().enumerate() {
            let gain = 2.0 * self.exposure[j] * spectrum.mean_speeds[j];
            for m in 0..modes {
                let phi = shapes[(j, m)];
                mean[m] += phi * floor_means[j];
                series[m].iter_mut().zip(v).for_each(|(q, x)| *q += phi * gain * x);
            }
        }
        Ok(CoarseModalForces { mean, fluctuations: CoarseSeries { step: speeds.step, series } })
    }
}
