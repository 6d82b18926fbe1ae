//! The reference model's peak responses, for `windmeta sample-peaks`: a reduced-order run gives
//! every response through the same equations as the metamodel's ([`ResponseView`], with the
//! integrator's own velocities); a full-order run gives the displacements, drifts, strokes and
//! damper forces of its floors (velocities by central differences), not accelerations, which would
//! need the full equations of motion.

use super::response::damper_below;
use super::{Response, ResponseView};
use crate::dynamics::{ModalMotion, SampleModel};
use crate::error::{Error, Result};
use crate::problem::{Problem, StormRun};

/// The peak of `response` in the reference run `run` of inputs `x`.
pub fn reference_peak(problem: &Problem, x: &[f64], run: &StormRun, response: Response) -> Result<f64> {
    response.check(&problem.structure)?;
    let p = problem.parameters(x)?;
    let dampers = problem.dampers(&p)?;
    if let (Some(motion), Some(forces)) = (&run.modal_motion, &run.modal_forces) {
        let modes = problem.sample_modes(&p);
        let shapes: Vec<Vec<f64>> = (0..modes.count())
            .map(|m| (0..problem.structure.floors()).map(|f| modes.shapes[(f, m)]).collect())
            .collect();
        let model = SampleModel::new(&modes, p.damping_ratio, &dampers);
        return response.peak(&ResponseView::new(&shapes, &problem.structure, motion, &model, forces));
    }
    let Some(floors) = &run.floor_displacements else {
        return Err(Error::Internal("a reference run without its histories".into()));
    };
    let at = |floor: usize| -> &[f64] { &floors[floor - 1] };
    let storey = |floor: usize| -> Vec<f64> {
        if floor == 1 { at(1).to_vec() } else { at(floor).iter().zip(at(floor - 1)).map(|(a, b)| a - b).collect() }
    };
    let peak = |history: &[f64]| history.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    Ok(match response {
        Response::Displacement { floor } => peak(at(floor)),
        Response::Drift { floor } => peak(&storey(floor)),
        Response::DamperStroke { floor } => {
            problem.structure.dampers[damper_below(&problem.structure, floor)?].cos_angle * peak(&storey(floor))
        }
        Response::DamperForce { floor } => {
            // The damper's axial displacement (a combination of floors), then its velocity.
            let d = damper_below(&problem.structure, floor)?;
            let steps = problem.storm.steps();
            let axial: Vec<f64> =
                (0..steps).map(|t| dampers.floor_weights[d].iter().map(|&(f, w)| w * floors[f][t]).sum()).collect();
            let motion = ModalMotion::from_displacements(vec![axial], problem.storm.time_step);
            let fastest = motion.velocities[0].iter().fold(0.0, |m: f64, v| m.max(v.abs()));
            dampers.force(d, fastest).abs()
        }
        Response::Acceleration { .. } => {
            return Err(Error::invalid(
                "response",
                "the full-order reference reports displacements, drifts, strokes and damper forces; accelerations come from the reduced order",
            ));
        }
    })
}
