//! What an analysis asks of its storms: their inputs and wind streams ([`Draws`]), and what a
//! diverging free run does ([`OnDivergence`]); shared by the metamodel's and the reference's runs.

use crate::study::Study;
use serde::{Deserialize, Serialize};

/// The storms an analysis runs through the metamodel: row i's physical inputs, and the stream of
/// the run seeded with `seed` its wind is drawn from (two rows with the same stream see the same
/// storm phases, which common random numbers and Sobol's pick-freeze designs rely on).
pub struct Draws<'a> {
    /// The study the storms are drawn in (structure, input model, storm duration and step).
    pub study: &'a Study,
    /// The physical inputs of each storm, one row per storm.
    pub rows: &'a [Vec<f64>],
    /// The stream of `seed` each row's wind is drawn from, one per row.
    pub storms: &'a [usize],
    /// The seed whose streams the winds are drawn from.
    pub seed: u64,
    /// What a storm whose free run diverges does to the analysis.
    pub on_divergence: OnDivergence,
}

/// What a storm whose metamodel free run diverges does to an analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OnDivergence {
    /// The analysis fails, naming the sample (where every peak is needed: moments, Sobol indices).
    Fail,
    /// Its peak is taken as infinite: it exceeds every threshold (conservative; counted and reported
    /// by the analyses that allow it).
    Exceed,
}
