//! What a calibration will cost, estimated from the study and the options before any storm is run,
//! so that a service can refuse a request that would exhaust the machine instead of queueing it.
//!
//! The estimate counts the large buffers of each phase, in bytes, and the storm steps integrated;
//! the small ones (a storm's parameters, the NARX dictionary, the tables of one study) are left
//! out. Against the peak resident size of `windmeta calibrate` (frame40-kn, 3 modes, 2 threads,
//! `/usr/bin/time -v`), which includes the allocator's per-thread caches and the study itself:
//! 0.164 GB of buffers for 0.291 GB measured at the paper's size (K = 200, 900 s at 0.01 s), and
//! 0.552 GB for 0.945 GB with 3600 s storms and K = 40: a ratio of 1.7-1.8 in both, which
//! `MEMORY_OVERHEAD` rounds up.

use super::CalibrationOptions;
use crate::error::{Error, Result};
use crate::study::Study;

/// Measured peak resident size over the estimate of the buffers (1.7-1.8), rounded up.
const MEMORY_OVERHEAD: f64 = 2.0;
/// Most candidate polynomials of one expansion: the LARS path works on their Gram matrix, so
/// memory grows with their square (0.2 GB at 5000) and time with the square times the
/// experiments; the paper's basis has 1341.
pub const MAX_PCE_BASIS: f64 = 5000.0;

/// The dominant buffers and the work of one calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationCost {
    /// Estimated peak memory (bytes), overhead included, and the request field that drives most
    /// of it, so that a refusal can name what to change.
    pub memory_bytes: f64,
    /// The request field that drives most of the memory.
    pub memory_driver: &'static str,
    /// Storm steps integrated by the reference model: experiments × steps per storm.
    pub storm_steps: f64,
    /// Candidate polynomials of the largest expansion.
    pub pce_basis: f64,
}

impl CalibrationCost {
    /// The cost of calibrating `study` with `options` on `threads` worker threads.
    pub fn estimate(study: &Study, options: &CalibrationOptions, threads: usize) -> CalibrationCost {
        const F64: f64 = 8.0;
        let steps = study.storm.steps() as f64;
        let modes = study.modes.count() as f64;
        let threads = threads.max(1) as f64;
        let site = &study.wind.site;
        let generation_points = study.storm.duration / site.field_generation_step_s + 4.0;
        let transform_points = site.generation_transform_points();
        let inputs = study.inputs.inputs.len();
        let pce_basis = options.pce.basis_size_bound(inputs);
        let terms = options.narx.max_terms as f64;
        let selection = options.selection_experiments.min(options.experiments) as f64;
        let parts: [(&'static str, f64); 4] = [
            // The selection experiments' forces and displacements, kept until every mode's structure
            // is chosen, and each thread's experiment in flight: forces, displacements, their scaled
            // copies, the free run and the refinement's sensitivities (one column per term).
            ("duration_s", F64 * steps * (selection * 2.0 * modes + threads * (6.0 * modes + terms + 2.0))),
            // Each thread's wind workspace: the transform's three buffers of complex single-precision
            // points and the generated series of every mode, twice (sum and result).
            (
                "wind.field_generation_step_s",
                threads * (3.0 * F64 * transform_points + 2.0 * F64 * modes * generation_points),
            ),
            // Each thread's expansion fit: the design matrix and the Gram matrix of the LARS path.
            ("pce.max_degree", threads * F64 * (pce_basis * options.experiments as f64 + pce_basis * pce_basis)),
            // The design itself and the fitted coefficients: small unless the experiments are many.
            ("experiments", F64 * options.experiments as f64 * (inputs as f64 + modes * (terms + 2.0))),
        ];
        let (memory_driver, _) = parts.iter().copied().fold(("duration_s", 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let memory_bytes = MEMORY_OVERHEAD * parts.iter().map(|(_, bytes)| bytes).sum::<f64>();
        CalibrationCost { memory_bytes, memory_driver, storm_steps: options.experiments as f64 * steps, pce_basis }
    }

    /// Refuses a calibration beyond `max_memory_bytes` or `max_storm_steps`, or with an expansion
    /// basis beyond [`MAX_PCE_BASIS`], naming the field to change.
    pub fn check(&self, max_memory_bytes: f64, max_storm_steps: f64) -> Result<()> {
        if self.pce_basis > MAX_PCE_BASIS {
            return Err(Error::invalid(
                "pce",
                format!(
                    "max_degree and max_interaction give up to {:.0} candidate polynomials per expansion, more than \
                     {MAX_PCE_BASIS}; lower either",
                    self.pce_basis
                ),
            ));
        }
        if self.storm_steps > max_storm_steps {
            return Err(Error::invalid(
                "experiments",
                format!(
                    "experiments × steps per storm = {:.3e} storm steps exceeds this server's budget of {max_storm_steps:.3e}; \
                     use fewer experiments, a shorter storm or a longer time step",
                    self.storm_steps
                ),
            ));
        }
        if self.memory_bytes > max_memory_bytes {
            return Err(Error::invalid(
                self.memory_driver,
                format!(
                    "the calibration would need about {:.0} MiB, more than this server's {:.0} MiB per job; {} drives most of it",
                    self.memory_bytes / MIB,
                    max_memory_bytes / MIB,
                    self.memory_driver
                ),
            ));
        }
        Ok(())
    }
}

const MIB: f64 = 1024.0 * 1024.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_calibration_fits_the_default_budget_and_a_huge_one_does_not() {
        let study = Study::preset("frame40-kn").unwrap();
        let options = CalibrationOptions::default();
        let cost = CalibrationCost::estimate(&study, &options, 2);
        assert_eq!(cost.storm_steps, 200.0 * 90_001.0);
        assert_eq!(cost.pce_basis, 1341.0);
        // The buffers (0.164 GB) times the overhead: above the 0.29 GB measured, within the budget.
        assert!((cost.memory_bytes - 2.0 * 0.1645e9).abs() < 0.005e9, "{cost:?}");
        assert!(cost.check(4096.0 * MIB, 1e9).is_ok());

        let day = study.clone().with_storm(86_400.0, 0.01).unwrap();
        let error = CalibrationCost::estimate(&day, &options, 2).check(4096.0 * MIB, 1e12).unwrap_err();
        assert!(error.to_string().starts_with("duration_s: the calibration would need about"), "{error}");
        let error = CalibrationCost::estimate(&study, &options, 2).check(4096.0 * MIB, 1e6).unwrap_err();
        assert!(error.to_string().starts_with("experiments:"), "{error}");

        let mut wide = options.clone();
        wide.pce.max_interaction = 8;
        let error = CalibrationCost::estimate(&study, &wide, 2).check(4096.0 * MIB, 1e9).unwrap_err();
        assert!(error.to_string().starts_with("pce:"), "{error}");
    }
}
