//! Validation: a metamodel compared with the reference model on fresh storms, the same inputs and
//! the same wind through both.
//!
//! May import `responses`, `sampling`, `certification` and
//! `answers` (it uses only the first two).

pub(super) mod validate;
pub(super) mod validated_responses;
