//! Certification: an estimate of the metamodel corrected by storms run through both the reference
//! model and the metamodel, so that it is unbiased for the reference model and its band carries
//! the metamodel's error; for an exceedance curve (storm by storm) and for an annual curve
//! (stratum by stratum).
//!
//! May import `responses` and `sampling`.

pub(super) mod certified_hazard;
pub(super) mod certify;
