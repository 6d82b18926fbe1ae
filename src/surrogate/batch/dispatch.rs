//! Instruction-set dispatch: the free run compiled for AVX-512, for AVX2 and portably, and the
//! choice among them by what the running processor has.

use super::dense::{self, DenseLinear};
use super::general::{self, TermLists};
use super::inputs::{Prepared, Workspace, lane_inputs};
use super::simd::Vector;
#[cfg(target_arch = "x86_64")]
use super::simd::{Avx2, Avx2Isa, Avx512, Avx512Isa};
use super::sink::{Divergence, Sink};
use super::{BatchSample, Lanes};

/// A batch's models compiled for the free run, and the storm they run over.
pub(super) struct Compiled {
    /// Each mode's rest state, every lane: its outputs before t = 0.
    pub rests: Vec<Lanes>,
    /// 1 / input scale per mode.
    pub inverse_scales: Vec<f64>,
    pub recursion: Recursion,
    /// The storm's steps, and their length in seconds.
    pub steps: usize,
    pub time_step: f64,
}

/// How the steps are computed.
pub(super) enum Recursion {
    /// Dense arrays with the modes and lags fixed at compile time: the paper's structures.
    Dense(DenseLinear),
    /// Term lists: any structure.
    TermLists(TermLists),
}

/// Runs the compiled batch on the widest vectors the processor has.
pub(super) fn free_run(
    compiled: &Compiled,
    samples: &[BatchSample],
    workspace: &mut Workspace,
    sink: &mut Sink,
) -> Result<(), Divergence> {
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(isa) = Avx512Isa::detect() {
            // SAFETY: `isa` was detected, so the processor has the features the function is
            // compiled for.
            return unsafe { free_run_avx512(isa, compiled, samples, workspace, sink) };
        }
        if let Some(isa) = Avx2Isa::detect() {
            // SAFETY: as above.
            return unsafe { free_run_avx2(isa, compiled, samples, workspace, sink) };
        }
    }
    free_run_on::<Lanes>((), compiled, samples, workspace, sink)
}

/// [`free_run_on`] compiled for the features of a vector type, so that its intrinsics inline.
macro_rules! compiled_for {
    ($name:ident, $vector:ident, $features:literal) => {
        /// # Safety
        /// The processor must have the features the function is compiled for, which `isa` proves.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        unsafe fn $name(
            isa: <$vector as Vector>::Isa,
            compiled: &Compiled,
            samples: &[BatchSample],
            workspace: &mut Workspace,
            sink: &mut Sink,
        ) -> Result<(), Divergence> {
            free_run_on::<$vector>(isa, compiled, samples, workspace, sink)
        }
    };
}

compiled_for!(free_run_avx512, Avx512, "avx512f,fma");
compiled_for!(free_run_avx2, Avx2, "avx2,fma");

/// The inputs into the workspace, then the recursion, on the vectors V. Everything here inlines
/// into its caller, so that it is compiled for the caller's features; nothing may go through a
/// closure that is not (a thread-local's accessor once did, and the AVX-512 intrinsics became
/// calls: a tenfold slower free run).
#[inline(always)]
fn free_run_on<V: Vector>(
    isa: V::Isa,
    compiled: &Compiled,
    samples: &[BatchSample],
    workspace: &mut Workspace,
    sink: &mut Sink,
) -> Result<(), Divergence> {
    let (steps, time_step) = (compiled.steps, compiled.time_step);
    let schedule = lane_inputs(samples, &compiled.inverse_scales, steps, time_step, workspace);
    let prepared = Prepared { rests: &compiled.rests, schedule, coarse: &workspace.inputs, steps };
    match &compiled.recursion {
        Recursion::Dense(models) => dense::run::<V>(isa, models, &prepared, sink),
        Recursion::TermLists(lists) => general::run(lists, &prepared, sink),
    }
}
