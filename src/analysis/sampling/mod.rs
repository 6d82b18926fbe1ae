//! Sampling and its estimators: storms drawn from the input model (or a climate's strata) and run
//! through the metamodel, or through both the reference model and the metamodel; the wind climate;
//! and the estimators of what the storms say: exceedance curves with their Clopper-Pearson bands,
//! stratified annual probabilities, one stratified sample read as several columns.
//!
//! May import `responses` only.

pub(super) mod annual_sample;
pub(super) mod climate;
pub(super) mod draws;
pub(super) mod exceedance;
pub(super) mod reference_storms;
pub(super) mod runner;
pub(super) mod storms;
pub(super) mod strata;
