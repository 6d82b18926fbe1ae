//! The batch's unit: how many samples advance through the free run together, and their values as
//! one array. Shared by the batch and the vector types that compute on it.

/// Samples per batch: one AVX-512 register of f64, two AVX2 ones.
pub const LANES: usize = 8;

/// One value of every sample of a batch.
pub type Lanes = [f64; LANES];
