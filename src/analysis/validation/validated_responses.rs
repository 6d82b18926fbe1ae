//! The responses a validation judges a metamodel by: the roof displacement, the largest drift, the
//! roof acceleration (peak and RMS) and the largest damper force, each compared storm for storm
//! with the reference.
//!
//! "Largest" is a floor, not an envelope: the floor (or damper) whose peak is largest on average
//! over the reference samples, so that both models are compared on the same named response.

use crate::analysis::responses::peaks::{pearson, quantile};
use crate::analysis::responses::response::{Response, ResponseKind, ResponseView};
use crate::analysis::sampling::exceedance::max_exceedance_gap;
use crate::error::Result;
use serde::{Deserialize, Serialize};

/// One sample's peaks of every response a validation checks.
#[derive(Debug, Clone)]
pub struct CheckedPeaks {
    roof_displacement: f64,
    roof_acceleration: f64,
    roof_rms_acceleration: f64,
    /// Per floor, from the first.
    drifts: Vec<f64>,
    /// Per damper floor (the floors with a damper below), with the floor.
    damper_forces: Vec<(usize, f64)>,
}

impl CheckedPeaks {
    /// The sample's peak roof displacement (m).
    pub fn roof_displacement(&self) -> f64 {
        self.roof_displacement
    }

    /// The peaks of every checked response in the sample `view` shows.
    pub fn of(view: &ResponseView) -> Result<CheckedPeaks> {
        let floors = view.structure.floors();
        let drifts = (1..=floors).map(|floor| Response::Drift { floor }.peak(view)).collect::<Result<_>>()?;
        let damper_forces = view
            .structure
            .dampers
            .iter()
            .map(|d| {
                let floor = d.upper_floor + 1;
                Ok((floor, Response::DamperForce { floor }.peak(view)?))
            })
            .collect::<Result<_>>()?;
        Ok(CheckedPeaks {
            roof_displacement: Response::Displacement { floor: floors }.peak(view)?,
            roof_acceleration: Response::Acceleration { floor: floors }.peak(view)?,
            roof_rms_acceleration: Response::RmsAcceleration { floor: floors }.peak(view)?,
            drifts,
            damper_forces,
        })
    }
}

/// How closely the metamodel's peaks of one response follow the reference's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ResponseValidation {
    /// `displacement`, `drift`, `acceleration`, `rms_acceleration` or `damper_force`.
    pub response: ResponseKind,
    /// The floor (for a damper force, the floor above the damper).
    pub floor: usize,
    /// Unit of the peaks: m, m/s² or N.
    pub unit: String,
    /// Mean of the reference peaks (for `rms_acceleration`, of the RMS values).
    pub mean_reference_peak: f64,
    /// Mean of the metamodel's peaks on the same storms: beside the reference's, the bias.
    #[serde(default)]
    pub mean_metamodel_peak: f64,
    /// Pearson correlation of the peaks, reference against metamodel.
    pub peak_correlation: f64,
    /// Median over the storms of |peak_meta − peak_ref| / |peak_ref|.
    pub median_peak_relative_error: f64,
    /// 95th percentile over the storms of the same relative error.
    pub p95_peak_relative_error: f64,
    /// Largest vertical gap between the two empirical exceedance curves of the peaks.
    pub max_exceedance_gap: f64,
}

impl ResponseValidation {
    fn of(kind: ResponseKind, floor: usize, reference: &[f64], metamodel: &[f64]) -> ResponseValidation {
        let mut errors: Vec<f64> = reference.iter().zip(metamodel).map(|(r, m)| (m - r).abs() / r.abs()).collect();
        errors.sort_by(f64::total_cmp);
        ResponseValidation {
            response: kind,
            floor,
            unit: kind.at_floor(floor).unit().into(),
            mean_reference_peak: mean(reference),
            mean_metamodel_peak: mean(metamodel),
            peak_correlation: pearson(reference, metamodel),
            median_peak_relative_error: quantile(&errors, 0.5),
            p95_peak_relative_error: quantile(&errors, 0.95),
            max_exceedance_gap: max_exceedance_gap(reference, metamodel),
        }
    }
}

/// The figures of every checked response, sample `k` of both lists being the same inputs and storm.
pub fn compare(reference: &[CheckedPeaks], metamodel: &[CheckedPeaks]) -> Vec<ResponseValidation> {
    let column =
        |peaks: &[CheckedPeaks], pick: &dyn Fn(&CheckedPeaks) -> f64| -> Vec<f64> { peaks.iter().map(pick).collect() };
    let Some(first) = reference.first() else { return Vec::new() };
    let floors = first.drifts.len();
    let total = |pick: &dyn Fn(&CheckedPeaks) -> f64| column(reference, pick).iter().sum::<f64>();
    let largest = |count: usize, pick: &dyn Fn(&CheckedPeaks, usize) -> f64| -> Option<usize> {
        (0..count).max_by(|&a, &b| total(&|p| pick(p, a)).total_cmp(&total(&|p| pick(p, b))))
    };
    let mut out = Vec::new();
    let mut add = |kind: ResponseKind, floor: usize, pick: &dyn Fn(&CheckedPeaks) -> f64| {
        out.push(ResponseValidation::of(kind, floor, &column(reference, pick), &column(metamodel, pick)));
    };
    add(ResponseKind::Displacement, floors, &|p| p.roof_displacement);
    if let Some(i) = largest(floors, &|p, i| p.drifts[i]) {
        add(ResponseKind::Drift, i + 1, &|p| p.drifts[i]);
    }
    add(ResponseKind::Acceleration, floors, &|p| p.roof_acceleration);
    add(ResponseKind::RmsAcceleration, floors, &|p| p.roof_rms_acceleration);
    if let Some(i) = largest(first.damper_forces.len(), &|p, i| p.damper_forces[i].1) {
        add(ResponseKind::DamperForce, first.damper_forces[i].0, &|p| p.damper_forces[i].1);
    }
    out
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}
