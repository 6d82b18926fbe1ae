//! PC-NARX metamodels (sections 3.2-3.3): NARX dynamics per retained mode whose coefficients are
//! sparse polynomial-chaos expansions of the uncertain inputs.

pub mod identify;
pub mod lars;
pub mod narx;
pub mod pce;
