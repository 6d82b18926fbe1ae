//! Quasi-steady floor forces (Eq. 14, linearised) and the modal forces Q = Φᵀ f, by the full field
//! or directly from the projected cross-spectral matrix.

use super::spectral::{SpectralGrid, simulate};
use super::spectrum::{FieldSpectrum, ProjectedSpectrum};
use super::{StormGrid, WindSite};
use crate::error::{Error, Result};
use crate::structure::Structure;
use crate::uncertainty::Rng;
use faer::{Mat, MatRef};

/// The wind model of one building at one site.
#[derive(Debug, Clone)]
pub struct WindLoads {
    pub site: WindSite,
    /// Floor elevations z_j (m).
    pub heights: Vec<f64>,
    /// η_j = ½ ρ C̄ A_j with A_j = h_j W_j (kg/m): f_j = η_j (v̄_j² + 2 v̄_j v_j).
    pub exposure: Vec<f64>,
}

/// Total wind force on every floor over a storm.
#[derive(Debug, Clone)]
pub struct FloorForces {
    /// Mean force on each floor (N).
    pub mean: Vec<f64>,
    /// Force history of each floor (N), mean included: `series[floor][step]`.
    pub series: Vec<Vec<f64>>,
}

/// Generalized forces of the retained modes over a storm.
#[derive(Debug, Clone)]
pub struct ModalForces {
    /// Mean generalized force of each mode (N).
    pub mean: Vec<f64>,
    /// History of each mode (N), mean included: `series[mode][step]`.
    pub series: Vec<Vec<f64>>,
}

impl FloorForces {
    /// Q_m(t) = Σ_j Φ_jm f_j(t).
    pub fn project(&self, shapes: MatRef<'_, f64>) -> ModalForces {
        let modes = shapes.ncols();
        let steps = self.series.first().map_or(0, Vec::len);
        let mut series = vec![vec![0.0; steps]; modes];
        let mut mean = vec![0.0; modes];
        for (j, floor) in self.series.iter().enumerate() {
            for m in 0..modes {
                let phi = shapes[(j, m)];
                mean[m] += phi * self.mean[j];
                series[m].iter_mut().zip(floor).for_each(|(q, f)| *q += phi * f);
            }
        }
        ModalForces { mean, series }
    }
}

impl WindLoads {
    pub fn new(site: &WindSite, structure: &Structure) -> Result<Self> {
        site.validate()?;
        if structure.floor_elevations[0] <= site.site_roughness_m {
            return Err(Error::invalid(
                "floor_elevations_m[0]",
                "the lowest floor must lie above the site's roughness length for the log profile to hold",
            ));
        }
        let half_rho_c = 0.5 * site.air_density_kg_m3 * site.pressure_coefficient;
        let exposure =
            structure.storey_heights().iter().zip(&structure.floor_widths).map(|(h, w)| half_rho_c * h * w).collect();
        Ok(WindLoads { site: site.clone(), heights: structure.floor_elevations.clone(), exposure })
    }

    pub fn spectrum(&self, wind_speed: f64) -> FieldSpectrum {
        FieldSpectrum::new(&self.site, &self.heights, wind_speed)
    }

    fn grid(&self) -> SpectralGrid {
        SpectralGrid { lines: self.site.frequencies, cutoff: self.site.cutoff_rad_s }
    }

    fn check_speed(wind_speed: f64) -> Result<()> {
        if wind_speed.is_finite() && wind_speed > 0.0 && wind_speed < 150.0 {
            Ok(())
        } else {
            Err(Error::invalid("inputs.wind_speed", format!("must lie in (0, 150) m/s, got {wind_speed}")))
        }
    }

    /// Mean floor forces η_j v̄_j² (N).
    pub fn mean_forces(&self, spectrum: &FieldSpectrum) -> Vec<f64> {
        self.exposure.iter().zip(&spectrum.mean_speeds).map(|(e, v)| e * v * v).collect()
    }

    /// The full field: the fluctuating speed at every floor, then the quasi-steady forces.
    pub fn floor_forces(&self, wind_speed: f64, storm: &StormGrid, rng: &mut Rng) -> Result<FloorForces> {
        Self::check_speed(wind_speed)?;
        let spectrum = self.spectrum(wind_speed);
        let speeds = simulate(&spectrum, &self.grid(), self.site.field_generation_step_s, storm, rng)?;
        let mean = self.mean_forces(&spectrum);
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

    /// The fast path: Q(t) = Φᵀ(η∘v̄²) + A v(t) with A = Φᵀ diag(2η_j v̄_j), simulated directly as an
    /// n_modes-variate process with cross-spectral matrix A S Aᵀ at the storm's own time step.
    pub fn modal_forces(
        &self,
        wind_speed: f64,
        shapes: MatRef<'_, f64>,
        storm: &StormGrid,
        rng: &mut Rng,
    ) -> Result<ModalForces> {
        Self::check_speed(wind_speed)?;
        let spectrum = self.spectrum(wind_speed);
        let floors = self.heights.len();
        let projection = Mat::from_fn(shapes.ncols(), floors, |m, j| {
            shapes[(j, m)] * 2.0 * self.exposure[j] * spectrum.mean_speeds[j]
        });
        let mean_forces = self.mean_forces(&spectrum);
        let mean: Vec<f64> =
            (0..shapes.ncols()).map(|m| (0..floors).map(|j| shapes[(j, m)] * mean_forces[j]).sum()).collect();
        let projected = ProjectedSpectrum { field: &spectrum, projection };
        let fluctuations = simulate(&projected, &self.grid(), storm.time_step, storm, rng)?;
        let series =
            fluctuations.into_iter().zip(&mean).map(|(q, mu)| q.into_iter().map(|x| x + mu).collect()).collect();
        Ok(ModalForces { mean, series })
    }
}
