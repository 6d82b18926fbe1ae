//! A storm's force histories: on every floor, on the modes over the storm's grid, and on the modes
//! over the wind's coarse generation grid, interpolated on demand. The metamodel's free run reads
//! the modal ones through [`ForceSource`], however they are held.

use super::StormGrid;
use super::spectral::CoarseSeries;
use crate::structure::spatial::plan_arms;
use faer::MatRef;

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
    /// The same forces times `factor` (a wider façade under the same wind, say).
    pub fn scaled(&self, factor: f64) -> FloorForces {
        let scale = |values: &[f64]| values.iter().map(|f| factor * f).collect::<Vec<f64>>();
        FloorForces { mean: scale(&self.mean), series: self.series.iter().map(|s| scale(s)).collect() }
    }

    /// The three-dimensional building's floor loads of these forces acting along the unit vector
    /// `direction` (cos β, sin β) at each plan's centre, for floors whose centres of mass lie at
    /// `centres_of_mass` from their plans' centres: on every floor the two components and their
    /// moment about the floor's centre of mass, as [`dof`](crate::structure::spatial::dof) numbers
    /// them. The along-wind drag of a plane study so placed drives the building as the plane frame
    /// (the check that the three-dimensional model reduces to it).
    pub fn on_plan(&self, direction: [f64; 2], centres_of_mass: &[[f64; 2]]) -> FloorForces {
        let arms: Vec<[f64; 3]> = centres_of_mass.iter().map(|&e| plan_arms(direction, e)).collect();
        let place =
            |values: &[f64]| -> Vec<f64> { values.iter().zip(&arms).flat_map(|(f, arm)| arm.map(|a| a * f)).collect() };
        let series = self
            .series
            .iter()
            .zip(&arms)
            .flat_map(|(floor, arm)| arm.map(|a| floor.iter().map(|f| a * f).collect::<Vec<f64>>()))
            .collect();
        FloorForces { mean: place(&self.mean), series }
    }

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

/// Modal forces on the generation grid, before interpolation to a storm's time step.
#[derive(Debug, Clone)]
pub struct CoarseModalForces {
    /// Mean generalized force of each mode (N).
    pub mean: Vec<f64>,
    /// The fluctuating parts (N).
    pub fluctuations: CoarseSeries,
}

impl CoarseModalForces {
    /// Mode m's total force at instants first, first + 1, … of a grid of step `time_step`.
    pub fn fill(&self, m: usize, time_step: f64, first: usize, out: &mut [f64]) {
        self.fluctuations.interpolate_into(m, time_step, first, self.mean[m], out);
    }

    /// Every mode on `storm`'s grid.
    pub fn on_grid(&self, storm: &StormGrid) -> ModalForces {
        let series = (0..self.mean.len())
            .map(|m| {
                let mut out = vec![0.0; storm.steps()];
                self.fill(m, storm.time_step, 0, &mut out);
                out
            })
            .collect();
        ModalForces { mean: self.mean.clone(), series }
    }
}

/// The modal forces of one storm, however they are held.
pub trait ForceSource: Sync {
    /// Mean generalized force of mode m (N).
    fn mean(&self, m: usize) -> f64;
    /// Mode m's force (N) at steps first, first + 1, … of the storm, into `out`.
    fn fill(&self, m: usize, time_step: f64, first: usize, out: &mut [f64]);
    /// The fluctuations on the wind's generation grid, where the forces come from one.
    fn coarse(&self) -> Option<&CoarseSeries> {
        None
    }
}

impl ForceSource for ModalForces {
    fn mean(&self, m: usize) -> f64 {
        self.mean[m]
    }
    fn fill(&self, m: usize, _: f64, first: usize, out: &mut [f64]) {
        out.copy_from_slice(&self.series[m][first..first + out.len()]);
    }
}

impl ForceSource for CoarseModalForces {
    fn mean(&self, m: usize) -> f64 {
        self.mean[m]
    }
    fn fill(&self, m: usize, time_step: f64, first: usize, out: &mut [f64]) {
        CoarseModalForces::fill(self, m, time_step, first, out);
    }
    fn coarse(&self) -> Option<&CoarseSeries> {
        Some(&self.fluctuations)
    }
}
