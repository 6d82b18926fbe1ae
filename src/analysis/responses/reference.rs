//! The reference model's responses, histories and peaks, for `windmeta simulate` and
//! `windmeta sample-peaks`: a reduced-order run gives every response through the same equations as
//! the metamodel's ([`ResponseView`], with the integrator's own velocities); a full-order run reads
//! them off its floors' motion, with Newmark's own velocities (damper forces) and accelerations,
//! which satisfy every floor's equation of motion at every step.

use super::response::{Response, ResponseView, damper_below, envelope};
use crate::dynamics::SampleModel;
use crate::error::{Error, Result};
use crate::study::{StormRun, Study};

/// The peak (for an RMS acceleration, the RMS) of `response` in the reference run `run` of inputs `x`.
pub fn reference_peak(study: &Study, x: &[f64], run: &StormRun, response: Response) -> Result<f64> {
    Ok(response.of_history(&reference_history(study, x, run, response)?, study.storm.time_step))
}

/// The history of `response` in the reference run `run` of inputs `x`; a damper group's envelope
/// step by step.
pub fn reference_history(study: &Study, x: &[f64], run: &StormRun, response: Response) -> Result<Vec<f64>> {
    let structure = &study.structure;
    let members = response.members(structure)?;
    let Some(floor) = response.floor() else {
        return envelope(members.into_iter().map(|m| reference_history(study, x, run, m)));
    };
    let p = study.parameters(x)?;
    let dampers = study.dampers(&p)?;
    if let (Some(motion), Some(forces)) = (&run.modal_motion, &run.modal_forces) {
        let modes = study.sample_modes(&p);
        let shapes: Vec<Vec<f64>> =
            (0..modes.count()).map(|m| (0..structure.floors()).map(|f| modes.shapes[(f, m)]).collect()).collect();
        let model = SampleModel::new(&modes, p.damping_ratio, &dampers);
        return response.history(&ResponseView::new(&shapes, structure, motion, &model, forces, study.storm.time_step));
    }
    let Some(full) = &run.floor_motion else {
        return Err(Error::Internal("a reference run without its histories".into()));
    };
    let at = |floor: usize| -> &[f64] { &full.displacements[floor - 1] };
    let storey = |floor: usize| -> Vec<f64> {
        if floor == 1 { at(1).to_vec() } else { at(floor).iter().zip(at(floor - 1)).map(|(a, b)| a - b).collect() }
    };
    Ok(match response {
        Response::Displacement { .. } => at(floor).to_vec(),
        Response::Drift { .. } => storey(floor),
        Response::Acceleration { .. } | Response::RmsAcceleration { .. } => full.accelerations[floor - 1].clone(),
        Response::DamperStroke { .. } => {
            let cos = structure.dampers[damper_below(structure, floor)?].cos_angle;
            storey(floor).iter().map(|u| cos * u).collect()
        }
        _ => {
            // A damper force: the law at the damper's axial velocity, from the floors' velocities.
            let d = damper_below(structure, floor)?;
            let axial =
                |t: usize| -> f64 { dampers.floor_weights[d].iter().map(|&(f, w)| w * full.velocities[f][t]).sum() };
            (0..study.storm.steps()).map(|t| dampers.force(d, axial(t))).collect()
        }
    })
}
