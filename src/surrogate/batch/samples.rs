//! What a batch is given: each mode's model (its terms and input scale, shared by every sample)
//! and each sample's coefficients and forces.

use super::super::damper_law::DamperLaw;
use super::super::narx::NarxTerm;
use crate::wind::ForceSource;

/// One mode's model as the batch runs it: the terms, and how its series are scaled.
#[derive(Debug, Clone, Copy)]
pub struct ModeProgram<'a> {
    /// The mode's NARX terms, in the order of its coefficients.
    pub terms: &'a [NarxTerm],
    /// The NARX reads (Q − Q̄)/input_scale.
    pub input_scale: f64,
    /// The law of velocity terms (the same for every mode); `None` where there are none.
    pub law: Option<&'a DamperLaw>,
}

/// One sample of a batch: its coefficients and forces.
pub struct BatchSample<'a> {
    /// `theta[m]`: the NARX coefficients of mode m, in the order of its terms.
    pub theta: Vec<Vec<f64>>,
    /// The sample's modal forces.
    pub forces: &'a dyn ForceSource,
}

/// The longest lag, input or output, of any term of any mode: how far back a step reads.
pub(super) fn longest_lag(programs: &[ModeProgram]) -> usize {
    programs.iter().flat_map(|p| p.terms.iter()).map(NarxTerm::reach).max().unwrap_or(0)
}
