//! Synchronous floor force records from a wind-tunnel test (a pressure model's taps integrated
//! floor by floor, or a multi-level force balance): per measured wind direction, each floor's force
//! along x and y and its torque about the plan's centre, as sampled on the model. They are the
//! whole aerodynamic load, mean included: drag, across-wind force and torque together, with their
//! true correlations.
//!
//! A rigid model's force coefficients are those of the building, so the records scale with the
//! length scale λ = L_building/L_model and the roof speeds U_H (the storm's) and U_m (the test's):
//! time t = t_m·λ·U_m/U_H, force F = F_m·(ρ/ρ_m)(U_H/U_m)²λ², torque T = T_m·(ρ/ρ_m)(U_H/U_m)²λ³.
//! A storm takes its loads from a window of the record at the direction measured nearest to its
//! own, starting at a uniformly random instant: storms drawn from one record are only as
//! independent as the record is long against them.

use crate::error::{Error, Result};
use crate::structure::spatial::{DOFS_PER_FLOOR, plan_arms};
use crate::uncertainty::Rng;
use crate::wind::{FloorForces, StormGrid};
use rand::RngExt;
use serde::Deserialize;

/// What a records file says of itself in its `format` field.
pub const RECORDS_FORMAT: &str = "floor_force_records";

/// At most this many values in a file (forces and torques of every floor, sample and direction):
/// 160 MB held in memory.
const MAX_VALUES: usize = 20_000_000;
/// At most this many directions (every degree).
const MAX_DIRECTIONS: usize = 360;

/// The records of one building, in model units.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorRecords {
    /// λ = L_building/L_model.
    pub length_scale: f64,
    /// U_m, the test's mean speed at the model's roof (m/s).
    pub model_roof_speed_m_s: f64,
    /// ρ_m of the test (kg/m³); `None`: the site's own.
    pub model_air_density_kg_m3: Option<f64>,
    /// The model's sampling rate (Hz).
    pub sampling_rate_hz: f64,
    /// The measured directions, increasing in [0°, 360°), with their records.
    directions: Vec<(f64, Records)>,
}

/// Every floor's records at one direction, `[floor][sample]`, floor 1 first.
#[derive(Debug, Clone, PartialEq)]
struct Records {
    force_x: Vec<Vec<f64>>,
    force_y: Vec<Vec<f64>>,
    torque: Vec<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordsFile {
    #[allow(dead_code)]
    format: String,
    length_scale: f64,
    model_roof_speed_m_s: f64,
    #[serde(default)]
    model_air_density_kg_m3: Option<f64>,
    sampling_rate_hz: f64,
    directions: Vec<DirectionFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DirectionFile {
    wind_direction_deg: f64,
    floors: Vec<FloorFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FloorFile {
    force_x_n: Vec<f64>,
    force_y_n: Vec<f64>,
    torque_n_m: Vec<f64>,
}

/// The scales of one storm: model time to building time, model force and torque to the building's.
#[derive(Debug, Clone, Copy)]
struct Scales {
    time: f64,
    force: f64,
    torque: f64,
}

impl FloorRecords {
    /// Reads the JSON text of a records file; errors name the field at fault.
    pub fn from_json(text: &str) -> Result<Self> {
        let file: RecordsFile = serde_json::from_str(text)
            .map_err(|e| Error::invalid("aerodynamics.records", format!("not a floor force records file: {e}")))?;
        for (name, value) in [
            ("length_scale", file.length_scale),
            ("model_roof_speed_m_s", file.model_roof_speed_m_s),
            ("sampling_rate_hz", file.sampling_rate_hz),
        ] {
            positive(name, value)?;
        }
        if let Some(density) = file.model_air_density_kg_m3 {
            positive("model_air_density_kg_m3", density)?;
        }
        if file.directions.is_empty() || file.directions.len() > MAX_DIRECTIONS {
            return Err(Error::invalid(
                "directions",
                format!("needs between 1 and {MAX_DIRECTIONS} directions, got {}", file.directions.len()),
            ));
        }
        let mut values = 0usize;
        let mut directions = Vec::with_capacity(file.directions.len());
        let first = &file.directions[0];
        let (floors, samples) = (first.floors.len(), first.floors.first().map_or(0, |f| f.force_x_n.len()));
        for (k, direction) in file.directions.into_iter().enumerate() {
            let degrees = direction.wind_direction_deg;
            if !(degrees.is_finite() && (0.0..360.0).contains(&degrees)) {
                return Err(Error::invalid(
                    format!("directions[{k}].wind_direction_deg"),
                    format!("must lie in [0, 360), got {degrees}"),
                ));
            }
            if direction.floors.len() != floors || floors == 0 {
                return Err(Error::invalid(
                    format!("directions[{k}].floors"),
                    format!(
                        "every direction needs the same floors (at least one), {floors} in the first, got {}",
                        direction.floors.len()
                    ),
                ));
            }
            values = values.saturating_add(DOFS_PER_FLOOR * floors * samples);
            if values > MAX_VALUES {
                return Err(Error::invalid("directions", format!("at most {MAX_VALUES} values in all")));
            }
            directions.push((degrees, records_of(k, direction.floors, samples)?));
        }
        directions.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(pair) = directions.windows(2).find(|pair| pair[0].0 == pair[1].0) {
            return Err(Error::invalid("directions", format!("{}° is given twice", pair[0].0)));
        }
        Ok(FloorRecords {
            length_scale: file.length_scale,
            model_roof_speed_m_s: file.model_roof_speed_m_s,
            model_air_density_kg_m3: file.model_air_density_kg_m3,
            sampling_rate_hz: file.sampling_rate_hz,
            directions,
        })
    }

    /// The floors each direction's records load.
    pub fn floors(&self) -> usize {
        self.directions[0].1.force_x.len()
    }

    /// The measured directions (degrees), increasing.
    pub fn directions(&self) -> Vec<f64> {
        self.directions.iter().map(|d| d.0).collect()
    }

    /// The measured direction nearest to `direction_deg` around the circle, and its index.
    pub fn nearest(&self, direction_deg: f64) -> Result<(usize, f64)> {
        if !direction_deg.is_finite() {
            return Err(Error::invalid("inputs.wind_direction", format!("must be finite, got {direction_deg}")));
        }
        let gap = |measured: f64| {
            let d = (measured - direction_deg).rem_euclid(360.0);
            d.min(360.0 - d)
        };
        let index = (0..self.directions.len())
            .min_by(|&a, &b| gap(self.directions[a].0).total_cmp(&gap(self.directions[b].0)))
            .unwrap_or(0);
        Ok((index, self.directions[index].0))
    }

    /// How long the records last at the building's scale for a roof speed `roof_speed` (m/s).
    pub fn duration_s(&self, roof_speed: f64) -> f64 {
        let samples = self.directions[0].1.force_x[0].len();
        (samples - 1) as f64 / self.sampling_rate_hz * self.time_scale(roof_speed)
    }

    fn time_scale(&self, roof_speed: f64) -> f64 {
        self.length_scale * self.model_roof_speed_m_s / roof_speed
    }

    fn scales(&self, roof_speed: f64, air_density: f64) -> Scales {
        let density_ratio = self.model_air_density_kg_m3.map_or(1.0, |model| air_density / model);
        let force = density_ratio * (roof_speed / self.model_roof_speed_m_s).powi(2) * self.length_scale.powi(2);
        Scales { time: self.time_scale(roof_speed), force, torque: force * self.length_scale }
    }

    /// One storm's loads on every degree of freedom (floor-major x, y, θ about each floor's centre
    /// of mass at `centres_of_mass` from its plan's centre): the records of the direction measured
    /// nearest to `direction_deg`, scaled to the roof speed `roof_speed` and air density
    /// `air_density`, from `start_s` (s, building scale) into the record. The mean is the whole
    /// record's, scaled: the static load the integrators start from.
    pub fn window(
        &self,
        direction_deg: f64,
        roof_speed: f64,
        air_density: f64,
        start_s: f64,
        centres_of_mass: &[[f64; 2]],
        storm: &StormGrid,
    ) -> Result<FloorForces> {
        let (index, _) = self.nearest(direction_deg)?;
        self.window_of(index, roof_speed, air_density, start_s, centres_of_mass, storm)
    }

    /// [`Self::window`] of the records of the measured direction `index`.
    fn window_of(
        &self,
        index: usize,
        roof_speed: f64,
        air_density: f64,
        start_s: f64,
        centres_of_mass: &[[f64; 2]],
        storm: &StormGrid,
    ) -> Result<FloorForces> {
        self.check_storm(index, roof_speed, start_s, storm)?;
        if centres_of_mass.len() != self.floors() {
            return Err(Error::Internal(format!(
                "{} centres of mass for records of {} floors",
                centres_of_mass.len(),
                self.floors()
            )));
        }
        let scales = self.scales(roof_speed, air_density);
        let records = &self.directions[index].1;
        let steps = storm.steps();
        // Model sample index of each storm instant.
        let per_step = storm.time_step / scales.time * self.sampling_rate_hz;
        let origin = start_s / scales.time * self.sampling_rate_hz;
        let resample = |record: &[f64], scale: f64| -> Vec<f64> {
            (0..steps)
                .map(|i| {
                    let position = origin + i as f64 * per_step;
                    let below = (position.floor() as usize).min(record.len() - 2);
                    let t = position - below as f64;
                    scale * ((1.0 - t) * record[below] + t * record[below + 1])
                })
                .collect()
        };
        let mean_of = |record: &[f64], scale: f64| scale * record.iter().sum::<f64>() / record.len() as f64;
        let mut mean = Vec::with_capacity(DOFS_PER_FLOOR * self.floors());
        let mut series = Vec::with_capacity(DOFS_PER_FLOOR * self.floors());
        for (j, &centre) in centres_of_mass.iter().enumerate() {
            let (fx, fy, torque) = (&records.force_x[j], &records.force_y[j], &records.torque[j]);
            // A force at the plan's centre acts on the centre of mass with the moment (−e) × F.
            let (arm_x, arm_y) = (plan_arms([1.0, 0.0], centre)[2], plan_arms([0.0, 1.0], centre)[2]);
            let x = resample(fx, scales.force);
            let y = resample(fy, scales.force);
            let mut twist = resample(torque, scales.torque);
            twist.iter_mut().zip(x.iter().zip(&y)).for_each(|(t, (x, y))| *t += arm_x * x + arm_y * y);
            let (mean_x, mean_y) = (mean_of(fx, scales.force), mean_of(fy, scales.force));
            mean.extend([mean_x, mean_y, mean_of(torque, scales.torque) + arm_x * mean_x + arm_y * mean_y]);
            series.extend([x, y, twist]);
        }
        Ok(FloorForces { mean, series })
    }

    /// [`Self::window`] from a start drawn uniformly over the instants the storm fits in.
    pub fn floor_forces(
        &self,
        direction_deg: f64,
        roof_speed: f64,
        air_density: f64,
        centres_of_mass: &[[f64; 2]],
        storm: &StormGrid,
        rng: &mut Rng,
    ) -> Result<FloorForces> {
        let (index, _) = self.nearest(direction_deg)?;
        self.check_storm(index, roof_speed, 0.0, storm)?;
        let slack = self.duration_s(roof_speed) - storm.duration;
        let start = rng.random::<f64>() * slack;
        self.window_of(index, roof_speed, air_density, start, centres_of_mass, storm)
    }

    /// The storm fits in the record from `start_s` at this roof speed.
    fn check_storm(&self, index: usize, roof_speed: f64, start_s: f64, storm: &StormGrid) -> Result<()> {
        positive("roof speed", roof_speed)?;
        let duration = self.duration_s(roof_speed);
        if !(start_s >= 0.0 && start_s + storm.duration <= duration * (1.0 + 1e-12)) {
            return Err(Error::invalid(
                format!("wind-tunnel directions[{index}]"),
                format!(
                    "the records last {duration:.1} s at the building's scale at a roof speed of {roof_speed:.1} m/s, \
                     too short for a storm of {} s from {start_s} s: a longer record or a shorter storm",
                    storm.duration
                ),
            ));
        }
        Ok(())
    }
}

fn positive(name: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(name, format!("must be positive and finite, got {value}")))
    }
}

/// One direction's floors checked: every record as long as the first direction's (`samples`, at
/// least two), every value finite.
fn records_of(k: usize, floors: Vec<FloorFile>, samples: usize) -> Result<Records> {
    let mut records = Records { force_x: Vec::new(), force_y: Vec::new(), torque: Vec::new() };
    for (j, floor) in floors.into_iter().enumerate() {
        for (name, values) in
            [("force_x_n", &floor.force_x_n), ("force_y_n", &floor.force_y_n), ("torque_n_m", &floor.torque_n_m)]
        {
            let field = format!("directions[{k}].floors[{j}].{name}");
            if values.len() != samples || samples < 2 {
                return Err(Error::invalid(
                    field,
                    format!(
                        "records are synchronous: {samples} samples (at least two) in every one, got {}",
                        values.len()
                    ),
                ));
            }
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(Error::invalid(format!("{field}[{i}]"), "must be finite"));
            }
        }
        records.force_x.push(floor.force_x_n);
        records.force_y.push(floor.force_y_n);
        records.torque.push(floor.torque_n_m);
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::rng_from_seed;
    use crate::wind::WindSite;
    use serde_json::{Value, json};
    use std::f64::consts::PI;

    /// Model sampling rate (Hz) and record frequency (Hz) of the test records: 200 samples a period.
    const RATE: f64 = 1000.0;
    const FREQUENCY: f64 = 5.0;

    /// Two floors sampled for 2 s: floor j's force along x is (j + 1)·(3 + 2 sin 2πft), along y the
    /// constant 0.5, its torque 0.7 cos 2πft (N, N·m).
    fn records(directions: &[f64]) -> Value {
        let samples = 2001;
        let wave = |f: &dyn Fn(f64) -> f64| -> Vec<f64> { (0..samples).map(|k| f(k as f64 / RATE)).collect() };
        let floor = |j: f64| {
            json!({
                "force_x_n": wave(&|t| (j + 1.0) * (3.0 + 2.0 * (2.0 * PI * FREQUENCY * t).sin())),
                "force_y_n": wave(&|_| 0.5),
                "torque_n_m": wave(&|t| 0.7 * (2.0 * PI * FREQUENCY * t).cos()),
            })
        };
        let directions: Vec<Value> =
            directions.iter().map(|&d| json!({"wind_direction_deg": d, "floors": [floor(0.0), floor(1.0)]})).collect();
        json!({
            "format": RECORDS_FORMAT,
            "length_scale": 200.0,
            "model_roof_speed_m_s": 10.0,
            "model_air_density_kg_m3": 1.2,
            "sampling_rate_hz": RATE,
            "directions": directions,
        })
    }

    fn read(file: &Value) -> Result<FloorRecords> {
        FloorRecords::from_json(&file.to_string())
    }

    /// At a roof speed of 40 m/s the time scale is 200·10/40 = 50 (the 5 Hz record turns 0.1 Hz,
    /// its 2 s last 100 s) and the force scale (1.25/1.2)·4²·200². Every resampled value equals
    /// the closed form at its model instant to the linear interpolation's error, (2π·5/1000)²/8 ≈
    /// 1.2·10⁻⁴ of the amplitude; the mean is the record's (whole periods and a last sample at a
    /// zero of the sine: exactly 3(j + 1) along x).
    /// The second floor's centre of mass sits at e = (1, −2) m, so its twist holds (−e) × F.
    #[test]
    fn a_window_is_the_record_at_the_buildings_scale() {
        let data = read(&records(&[0.0])).unwrap();
        let storm = StormGrid { duration: 50.0, time_step: 0.01 };
        let (roof_speed, density, start) = (40.0, 1.25, 20.0);
        let centres = [[0.0, 0.0], [1.0, -2.0]];
        let forces = data.window(0.0, roof_speed, density, start, &centres, &storm).unwrap();
        assert!((data.duration_s(roof_speed) - 100.0).abs() < 1e-9);
        let force_scale = 1.25 / 1.2 * 16.0 * 40_000.0;
        let torque_scale = force_scale * 200.0;
        for (j, centre) in centres.iter().enumerate() {
            let amplitude = (j + 1) as f64;
            let expected = |t: f64| {
                let phase = 2.0 * PI * FREQUENCY * (start + t) / 50.0;
                let (fx, fy) = (force_scale * amplitude * (3.0 + 2.0 * phase.sin()), force_scale * 0.5);
                let torque = torque_scale * 0.7 * phase.cos() + (-centre[0]) * fy - (-centre[1]) * fx;
                [fx, fy, torque]
            };
            for i in (0..storm.steps()).step_by(37) {
                let want = expected(i as f64 * storm.time_step);
                for (d, scale) in [force_scale * amplitude * 2.0, force_scale, torque_scale].into_iter().enumerate() {
                    let got = forces.series[3 * j + d][i];
                    assert!(
                        (got - want[d]).abs() <= 1.3e-4 * scale,
                        "floor {j}, dof {d}, step {i}: {got} vs {}",
                        want[d]
                    );
                }
            }
            let mean_x = force_scale * amplitude * 3.0;
            // The torque's 2 001 samples hold ten whole periods of the cosine and one more sample
            // at its crest: their mean is 0.7/2 001.
            let mean_torque = torque_scale * 0.7 / 2001.0;
            let mean_twist = mean_torque + (-centre[0]) * force_scale * 0.5 - (-centre[1]) * mean_x;
            assert!((forces.mean[3 * j] / mean_x - 1.0).abs() < 1e-12);
            assert!((forces.mean[3 * j + 2] - mean_twist).abs() <= 1e-9 * torque_scale, "{}", forces.mean[3 * j + 2]);
        }
    }

    #[test]
    fn the_nearest_measured_direction_is_found_around_the_circle() {
        let data = read(&records(&[90.0, 350.0, 0.0])).unwrap();
        assert_eq!(data.directions(), vec![0.0, 90.0, 350.0]);
        assert_eq!(data.nearest(359.0).unwrap().1, 0.0);
        assert_eq!(data.nearest(-8.0).unwrap().1, 350.0);
        assert_eq!(data.nearest(200.0).unwrap().1, 90.0);
        assert!(data.nearest(f64::NAN).is_err());
    }

    /// Random windows always fit: the last instant of the record bounds every draw. A storm longer
    /// than the record at its speed is refused, naming the direction and both durations.
    #[test]
    fn random_windows_fit_and_a_storm_longer_than_the_record_is_refused() {
        let data = read(&records(&[0.0])).unwrap();
        let site = WindSite::default();
        let mut rng = rng_from_seed(7);
        let storm = StormGrid { duration: 99.0, time_step: 0.5 };
        for _ in 0..50 {
            data.floor_forces(0.0, 40.0, site.air_density_kg_m3, &[[0.0; 2]; 2], &storm, &mut rng).unwrap();
        }
        let long = StormGrid { duration: 120.0, time_step: 0.5 };
        let refused = data.floor_forces(0.0, 40.0, 1.25, &[[0.0; 2]; 2], &long, &mut rng).unwrap_err().to_string();
        assert!(
            refused.contains("directions[0]") && refused.contains("100.0 s") && refused.contains("120 s"),
            "{refused}"
        );
    }

    #[test]
    fn broken_files_are_refused_by_the_field_at_fault() {
        let refused = |edit: &dyn Fn(&mut Value)| {
            let mut file = records(&[0.0, 90.0]);
            edit(&mut file);
            read(&file).unwrap_err().to_string()
        };
        assert!(refused(&|f| f["length_scale"] = json!(0.0)).starts_with("length_scale"));
        assert!(refused(&|f| f["model_roof_speed_m_s"] = json!(-3.0)).starts_with("model_roof_speed_m_s"));
        assert!(refused(&|f| f["directions"][1]["wind_direction_deg"] = json!(0.0)).contains("given twice"));
        assert!(
            refused(&|f| f["directions"][1]["wind_direction_deg"] = json!(360.0))
                .starts_with("directions[1].wind_direction_deg")
        );
        let shorter = refused(&|f| {
            f["directions"][1]["floors"][1]["torque_n_m"].as_array_mut().unwrap().pop();
        });
        assert!(shorter.starts_with("directions[1].floors[1].torque_n_m"), "{shorter}");
        let fewer = refused(&|f| {
            f["directions"][1]["floors"].as_array_mut().unwrap().pop();
        });
        assert!(fewer.starts_with("directions[1].floors"), "{fewer}");
        assert!(refused(&|f| f["directions"][0]["floors"][0]["force_y_n"][3] = json!("x")).contains("records file"));
        assert!(refused(&|f| f["surprise"] = json!(1)).contains("surprise"));
        let other = super::super::Aerodynamics::from_json(r#"{"format": "pressures"}"#).unwrap_err().to_string();
        assert!(other.starts_with("format") && other.contains(RECORDS_FORMAT), "{other}");
    }
}
