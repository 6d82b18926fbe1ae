//! Where an answer's storms run. Storms are an answer's cost — a free run of the metamodel each,
//! and for a certified answer a reference integration each for its reference storms — so the
//! service spreads them over every replica's workers in chunks, while the command line runs them
//! on this machine's cores (`OnThisMachine`). Whichever runs them, a storm's peaks depend only on
//! its row and its stream: the answer is the same to the bit.

use super::reference_storms::{PairedPeak, PairedRuns};
use super::storms::Draws;
use crate::analysis::responses::response::Response;
use crate::error::Result;
use crate::progress::Observer;
use crate::surrogate::Metamodel;

/// Runs an answer's storms.
pub trait StormRunner {
    /// `rows` (row i's wind from stream `storms[i]` of `runs.seed`) through both models of `runs`,
    /// in the order of the rows.
    fn pairs(
        &self,
        runs: &PairedRuns,
        rows: &[Vec<f64>],
        storms: &[usize],
        observer: &dyn Observer,
    ) -> Result<Vec<PairedPeak>>;

    /// Peaks of each of the floor responses `responses` for every row of `draws` through
    /// `metamodel` (`[row][response]`), in the order of the rows.
    fn floor_peak_sets(
        &self,
        metamodel: &Metamodel,
        draws: &Draws,
        responses: &[Response],
        observer: &dyn Observer,
    ) -> Result<Vec<Vec<f64>>>;
}
