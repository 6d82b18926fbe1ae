//! A study's storms and its reference runs: modal forces drawn for a sample (by the modal fast
//! path or the floor field), and one storm through the reduced- or full-order reference model.

use super::{PhysicalParameters, Study};
use crate::dynamics::{
    FloorResponse, ModalMotion, ModalResponse, ReducedStorm, integrate_full, integrate_reduced, integrate_reduced_lanes,
};
use crate::error::{Error, Result};
use crate::progress::{Observer, Silent};
use crate::simd::LANES;
use crate::uncertainty::{Rng, rng_from_seed, stream_seed};
use crate::wind::{CoarseModalForces, ModalForces, TransformWorkspace};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// How the wind of a reference run is generated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum WindPath {
    /// Every floor's speed, then Q = Φᵀ f.
    Field,
    /// The retained modes' forces directly from Φᵀ S_f Φ (equal in law, much cheaper).
    Modal,
}

/// Which reference model integrates the storm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// The retained modes' equations (exponential integrator).
    Reduced,
    /// Every floor's equation (Newmark).
    Full,
}

/// One storm through the reference model.
#[derive(Debug, Clone)]
pub struct StormRun {
    /// Roof displacement history (m), static part included.
    pub roof: Vec<f64>,
    /// Modal forces that drove it (for a full-order run, its floor forces projected on the
    /// retained modes: what a metamodel sees of the same storm).
    pub modal_forces: Option<ModalForces>,
    /// Modal displacements and the integrator's velocities of a reduced-order run.
    pub modal_motion: Option<ModalMotion>,
    /// Every floor's motion in a full-order run.
    pub floor_motion: Option<FloorResponse>,
    /// Time spent generating the wind (s).
    pub wind_seconds: f64,
    /// Time spent integrating (s).
    pub integration_seconds: f64,
}

impl StormRun {
    /// A reduced-order run: its modal response, the forces that drove it and its costs.
    fn reduced(response: ModalResponse, forces: ModalForces, wind_seconds: f64, integration_seconds: f64) -> Self {
        StormRun {
            roof: response.roof(),
            modal_forces: Some(forces),
            modal_motion: Some(response.motion()),
            floor_motion: None,
            wind_seconds,
            integration_seconds,
        }
    }

    /// Peak absolute roof displacement (m).
    pub fn peak(&self) -> f64 {
        self.roof.iter().fold(0.0, |m, x| m.max(x.abs()))
    }
}

impl Study {
    /// A storm's modal forces on the wind's generation grid, by the fast path or the full field,
    /// with the transforms of `workspace`.
    pub fn coarse_forces(
        &self,
        p: &PhysicalParameters,
        path: WindPath,
        workspace: &mut TransformWorkspace,
        rng: &mut Rng,
    ) -> Result<CoarseModalForces> {
        match path {
            WindPath::Modal => self.modal_wind.simulate(p.wind_speed, self.storm.duration, workspace, rng),
            WindPath::Field => {
                self.wind.projected_field(p.wind_speed, self.modes.shapes.as_ref(), self.storm.duration, workspace, rng)
            }
        }
    }

    /// A storm's modal forces on the storm's grid.
    pub fn modal_forces(&self, p: &PhysicalParameters, path: WindPath, rng: &mut Rng) -> Result<ModalForces> {
        Ok(self.coarse_forces(p, path, &mut TransformWorkspace::default(), rng)?.on_grid(&self.storm))
    }

    /// Sample k of a run seeded with `seed`: its physical parameters and its storm's modal forces on
    /// the generation grid. The storm depends only on (seed, k), whichever thread draws it and
    /// however many there are. `workspace` holds the wind's transforms; keep one per thread.
    pub fn sample_storm(
        &self,
        x: &[f64],
        path: WindPath,
        seed: u64,
        k: usize,
        workspace: &mut TransformWorkspace,
    ) -> Result<(PhysicalParameters, CoarseModalForces)> {
        let p = self.parameters(x)?;
        let forces = self.coarse_forces(&p, path, workspace, &mut rng_from_seed(stream_seed(seed, k as u64)))?;
        Ok((p, forces))
    }

    /// One storm through the reference model (not cancellable: for the command line). Full-order
    /// runs always use the floor field.
    pub fn reference_run(&self, x: &[f64], order: Order, path: WindPath, rng: &mut Rng) -> Result<StormRun> {
        let p = self.parameters(x)?;
        let dampers = self.dampers(&p)?;
        let dt = self.storm.time_step;
        match order {
            Order::Reduced => {
                let started = Instant::now();
                let forces = self.modal_forces(&p, path, rng)?;
                let wind_seconds = started.elapsed().as_secs_f64();
                let started = Instant::now();
                let response =
                    integrate_reduced(&self.sample_modes(&p), p.damping_ratio, &dampers, &forces, dt, &Silent)?;
                let integration_seconds = started.elapsed().as_secs_f64();
                Ok(StormRun::reduced(response, forces, wind_seconds, integration_seconds))
            }
            Order::Full => {
                let started = Instant::now();
                let forces = self.wind.floor_forces(p.wind_speed, &self.storm, rng)?;
                let wind_seconds = started.elapsed().as_secs_f64();
                let started = Instant::now();
                let system = self.full_system(&p);
                let response = integrate_full(&system, &dampers, &forces, dt, &Silent)?;
                let integration_seconds = started.elapsed().as_secs_f64();
                let roof = response.displacements.last().cloned().unwrap_or_default();
                Ok(StormRun {
                    roof,
                    modal_forces: Some(forces.project(self.modes.shapes.as_ref())),
                    modal_motion: None,
                    floor_motion: Some(response),
                    wind_seconds,
                    integration_seconds,
                })
            }
        }
    }

    /// Sampled storms (each sample's parameters and modal forces on the storm's grid) through the
    /// reduced-order reference, eight at a time in vector lanes: the responses of
    /// [`integrate_reduced`] one by one, to the damper solve's tolerance, at a fraction of the cost.
    pub fn integrate_reduced_batch(
        &self,
        samples: &[(PhysicalParameters, ModalForces)],
        observer: &dyn Observer,
    ) -> Result<Vec<ModalResponse>> {
        let mut responses = Vec::with_capacity(samples.len());
        for chunk in samples.chunks(LANES) {
            let models =
                chunk.iter().map(|(p, _)| Ok((self.sample_modes(p), self.dampers(p)?))).collect::<Result<Vec<_>>>()?;
            let storms: Vec<ReducedStorm<'_>> = chunk
                .iter()
                .zip(&models)
                .map(|((p, forces), (modes, dampers))| ReducedStorm {
                    modes,
                    damping_ratio: p.damping_ratio,
                    dampers,
                    forces,
                })
                .collect();
            responses.extend(integrate_reduced_lanes(&storms, self.storm.time_step, observer)?);
        }
        Ok(responses)
    }

    /// Storms through the reduced-order reference in vector lanes ([`Self::integrate_reduced_batch`]):
    /// storm i has the inputs `xs[i]` and its wind from `rngs[i]`, the runs of
    /// [`Self::reference_run`] one by one; a batch's integration time is shared equally among its
    /// storms.
    pub fn reduced_reference_runs(
        &self,
        xs: &[&[f64]],
        path: WindPath,
        rngs: &mut [Rng],
        observer: &dyn Observer,
    ) -> Result<Vec<StormRun>> {
        if xs.len() != rngs.len() {
            return Err(Error::invalid("storms", format!("{} inputs for {} wind streams", xs.len(), rngs.len())));
        }
        let mut workspace = TransformWorkspace::default();
        let started = Instant::now();
        let samples = xs
            .iter()
            .zip(rngs.iter_mut())
            .map(|(x, rng)| {
                let p = self.parameters(x)?;
                let forces = self.coarse_forces(&p, path, &mut workspace, rng)?.on_grid(&self.storm);
                Ok((p, forces))
            })
            .collect::<Result<Vec<_>>>()?;
        let wind_seconds = started.elapsed().as_secs_f64() / xs.len().max(1) as f64;
        let started = Instant::now();
        let responses = self.integrate_reduced_batch(&samples, observer)?;
        let integration_seconds = started.elapsed().as_secs_f64() / xs.len().max(1) as f64;
        Ok(samples
            .into_iter()
            .zip(responses)
            .map(|((_, forces), response)| StormRun::reduced(response, forces, wind_seconds, integration_seconds))
            .collect())
    }
}
