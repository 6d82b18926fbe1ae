//! Site and discretisation parameters of the wind model, with the paper's values as defaults.

use crate::error::{Error, Result, require_positive};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Everything about the wind that is not uncertain. Defaults are the paper's (section 4.2, App. 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(default, deny_unknown_fields)]
pub struct WindSite {
    /// Roughness length at the site, z₀ (m).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub site_roughness_m: f64,
    /// Roughness length at the meteorological station, z₀₁ (m).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub station_roughness_m: f64,
    /// Height of the station's anemometer, H_met (m); above its roughness length.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub station_height_m: f64,
    /// β of Eq. (20).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub shear_factor: f64,
    /// Von Kármán's constant k_a.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub von_karman: f64,
    /// C_z of the coherence, Eq. (22).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub coherence_decay: f64,
    /// Air density ρ (kg/m³).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub air_density_kg_m3: f64,
    /// Quasi-steady pressure coefficient C̄.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0))]
    pub pressure_coefficient: f64,
    /// Cut-off frequency ω_up (rad/s); the wind has no energy above 2π rad/s, and at most 60.
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 60))]
    pub cutoff_rad_s: f64,
    /// Frequencies per component, N (81 920 phases for 40 floors means 2048).
    #[cfg_attr(feature = "openapi", schema(minimum = 16, maximum = 65536))]
    #[serde(deserialize_with = "crate::count::count")]
    pub frequencies: usize,
    /// Time step on which the wind (the full floor field, or the modal forces directly) is
    /// generated before cubic interpolation to the storm's time step (s); it must resolve the
    /// cut-off (≤ π/ω_up), be at least 1 ms, and keep the generation transform within 2²² points
    /// (2πN/(ω_up·step) ≤ 4 194 304).
    #[cfg_attr(feature = "openapi", schema(minimum = 0.001))]
    pub field_generation_step_s: f64,
}

impl Default for WindSite {
    fn default() -> Self {
        WindSite {
            site_roughness_m: 0.02,
            station_roughness_m: 0.05,
            station_height_m: 10.0,
            shear_factor: 0.65,
            von_karman: 0.4,
            coherence_decay: 10.0,
            air_density_kg_m3: 1.25,
            pressure_coefficient: 1.3,
            cutoff_rad_s: 2.0 * PI,
            frequencies: 2048,
            field_generation_step_s: 0.1,
        }
    }
}

/// Largest cut-off frequency (rad/s): ten times the 2π rad/s above which the wind has no energy.
pub const MAX_CUTOFF_RAD_S: f64 = 60.0;
/// Finest generation step (s): the cubic interpolation to the storm grid makes a finer generation
/// grid than the storm's own pointless, and 1 ms resolves 500 Hz.
pub const MIN_GENERATION_STEP_S: f64 = 1e-3;
/// Largest transform the generation may use: its buffers (about 3·8 bytes a point) are kept per
/// thread, so 2²² points hold about 100 MB per thread.
pub const MAX_GENERATION_TRANSFORM: f64 = 4_194_304.0;

impl WindSite {
    /// Points of the transform a storm is generated with, before rounding to a fast length:
    /// 2π/(Δω·Δt_g) = 2πN/(ω_up·Δt_g).
    pub fn generation_transform_points(&self) -> f64 {
        2.0 * PI * self.frequencies as f64 / (self.cutoff_rad_s * self.field_generation_step_s)
    }

    /// Refuses a site whose parameters are out of range, naming the field.
    pub fn check(&self) -> Result<()> {
        require_positive("wind.site_roughness_m", self.site_roughness_m)?;
        require_positive("wind.station_roughness_m", self.station_roughness_m)?;
        require_positive("wind.station_height_m", self.station_height_m)?;
        if self.station_height_m <= self.station_roughness_m {
            return Err(Error::invalid("wind.station_height_m", "must exceed the station's roughness length"));
        }
        require_positive("wind.shear_factor", self.shear_factor)?;
        require_positive("wind.von_karman", self.von_karman)?;
        require_positive("wind.coherence_decay", self.coherence_decay)?;
        require_positive("wind.air_density_kg_m3", self.air_density_kg_m3)?;
        require_positive("wind.pressure_coefficient", self.pressure_coefficient)?;
        require_positive("wind.cutoff_rad_s", self.cutoff_rad_s)?;
        if self.cutoff_rad_s > MAX_CUTOFF_RAD_S {
            return Err(Error::invalid(
                "wind.cutoff_rad_s",
                format!("must be at most {MAX_CUTOFF_RAD_S} rad/s, got {}", self.cutoff_rad_s),
            ));
        }
        if !(16..=1 << 16).contains(&self.frequencies) {
            return Err(Error::invalid(
                "wind.frequencies",
                format!("must be between 16 and 65536, got {}", self.frequencies),
            ));
        }
        require_positive("wind.field_generation_step_s", self.field_generation_step_s)?;
        if self.field_generation_step_s < MIN_GENERATION_STEP_S {
            return Err(Error::invalid(
                "wind.field_generation_step_s",
                format!("must be at least {MIN_GENERATION_STEP_S} s, got {}", self.field_generation_step_s),
            ));
        }
        if self.field_generation_step_s > PI / self.cutoff_rad_s {
            return Err(Error::invalid(
                "wind.field_generation_step_s",
                format!("must resolve the cut-off frequency: at most π/ω_up = {:.4} s", PI / self.cutoff_rad_s),
            ));
        }
        let points = self.generation_transform_points();
        if points > MAX_GENERATION_TRANSFORM {
            return Err(Error::invalid(
                "wind.field_generation_step_s",
                format!(
                    "a generation transform of 2πN/(ω_up·step) = {points:.0} points exceeds {MAX_GENERATION_TRANSFORM}; \
                     raise the step or the cut-off, or lower wind.frequencies"
                ),
            ));
        }
        Ok(())
    }

    /// Mean hourly speed at height z (m) for a station speed v̄ (Eq. 13).
    pub fn mean_speed(&self, z: f64, station_speed: f64) -> f64 {
        let (z0, z01) = (self.site_roughness_m, self.station_roughness_m);
        0.8065 * (z0 / z01).powf(0.0706) * (z / z0).ln() / (self.station_height_m / z01).ln() * station_speed
    }

    /// Shear velocity v* (Eq. 20), with v̄₁₀ the site's own mean speed at 10 m from Eq. (13).
    pub fn shear_velocity(&self, station_speed: f64) -> f64 {
        let v10 = self.mean_speed(10.0, station_speed);
        v10 * self.shear_factor * self.von_karman / (10.0 / self.site_roughness_m).ln()
    }
}

/// The interval (s) at which an RMS acceleration samples the storm's acceleration. Every step's
/// acceleration needs every damper's force (a power each), which at 100 Hz made a metamodel's RMS
/// seventy times as costly as its peak; sampled at 10 Hz, nine samples a period of the highest
/// retained mode (7 rad/s), the RMS of six reference histories moved by at most 1.6·10⁻⁴ every 8th
/// step and 3.4·10⁻⁴ every 16th (docs/method.md). Reference and metamodel sample alike, so they are compared on one definition.
pub const RMS_SAMPLING_INTERVAL_S: f64 = 0.1;

/// Every how many steps of `time_step` (s) an RMS acceleration samples the storm.
pub fn rms_stride(time_step: f64) -> usize {
    ((RMS_SAMPLING_INTERVAL_S / time_step).round() as usize).max(1)
}

/// The time grid of one storm: `steps()` instants 0, Δt, …, T.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StormGrid {
    /// Storm duration T (s).
    pub duration: f64,
    /// Time step Δt (s).
    pub time_step: f64,
}

/// No storm longer than a day: anything longer is a typo, and memory grows with it.
pub const MAX_DURATION_S: f64 = 86_400.0;
/// Ten million instants per storm at most (80 MB per series).
pub const MAX_STEPS: usize = 10_000_000;
/// Finest time step (s): 10 kHz, a hundred times the paper's rate.
pub const MIN_TIME_STEP_S: f64 = 1e-4;

impl StormGrid {
    /// Checks the grid against itself and against the wind discretisation it must be simulated on.
    pub fn new(duration: f64, time_step: f64, site: &WindSite) -> Result<Self> {
        require_positive("duration_s", duration)?;
        require_positive("time_step_s", time_step)?;
        if duration > MAX_DURATION_S {
            return Err(Error::invalid("duration_s", format!("at most {MAX_DURATION_S} s (one day), got {duration}")));
        }
        if time_step < MIN_TIME_STEP_S {
            return Err(Error::invalid(
                "time_step_s",
                format!("must be at least {MIN_TIME_STEP_S} s, got {time_step}"),
            ));
        }
        if time_step > PI / site.cutoff_rad_s {
            return Err(Error::invalid(
                "time_step_s",
                format!("must resolve the wind's cut-off frequency: at most π/ω_up = {:.4} s", PI / site.cutoff_rad_s),
            ));
        }
        if time_step > duration {
            return Err(Error::invalid("time_step_s", "must not exceed the duration"));
        }
        let grid = StormGrid { duration, time_step };
        if grid.steps() > MAX_STEPS {
            return Err(Error::invalid(
                "time_step_s",
                format!("{} instants exceed the limit of {MAX_STEPS}; use a longer time step", grid.steps()),
            ));
        }
        Ok(grid)
    }

    /// Number of instants, both ends included.
    pub fn steps(&self) -> usize {
        (self.duration / self.time_step).round() as usize + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. (13) with the paper's constants reduces to v̄_z = 0.1427 ln(z/0.02) v̄; v* = 0.0418 v̄₁₀.
    #[test]
    fn profile_and_shear_velocity_match_the_reduced_constants() {
        let site = WindSite::default();
        let factor = 0.8065 * 0.4f64.powf(0.0706) / 200f64.ln();
        assert!((factor - 0.1427).abs() < 5e-5);
        assert!((site.mean_speed(154.3, 30.0) - factor * (154.3f64 / 0.02).ln() * 30.0).abs() < 1e-12);
        let v10 = site.mean_speed(10.0, 30.0);
        assert!((site.shear_velocity(30.0) / v10 - 0.0418).abs() < 5e-5);
    }

    #[test]
    fn absurd_grids_are_refused() {
        let site = WindSite::default();
        assert!(StormGrid::new(900.0, 0.01, &site).is_ok());
        assert!(StormGrid::new(-1.0, 0.01, &site).unwrap_err().to_string().starts_with("duration_s"));
        assert!(StormGrid::new(1e9, 0.01, &site).is_err());
        assert!(StormGrid::new(900.0, 0.0, &site).unwrap_err().to_string().starts_with("time_step_s"));
        assert!(StormGrid::new(900.0, 1.0, &site).unwrap_err().to_string().contains("cut-off"));
        assert!(StormGrid::new(86_400.0, 1e-4, &site).unwrap_err().to_string().contains("exceed"));
        assert!(StormGrid::new(f64::NAN, 0.01, &site).is_err());
    }
}
