//! The one error type of the numerical core.
//!
//! Bad input names the field at fault so that the command line can print it and the service can put
//! it in a problem+json `errors[]` entry without parsing strings.

use serde::{Deserialize, Serialize};
use std::fmt;

/// What went wrong in the numerical core. Serialisable so that an error met on one replica's
/// worker reaches the job it belongs to with its kind intact.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Error {
    /// The caller supplied something unusable; `field` names it (`stiffness`, `inputs.wind_speed`, ...).
    Invalid {
        /// The field at fault, as the request or file names it.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The computation itself failed on valid input (a diverging free run, a failed factorisation).
    Numerical(String),
    /// The caller asked the work to stop.
    Cancelled,
    /// Something outside the request failed: the database, the runtime, a thread that panicked.
    /// Neither bad input nor numerics, so the command line gives it its own exit code (3).
    Internal(String),
}

impl Error {
    /// An [`Error::Invalid`] naming `field` and saying what is wrong with it.
    pub fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Invalid { field: field.into(), reason: reason.into() }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Invalid { field, reason } => write!(f, "{field}: {reason}"),
            Error::Numerical(message) => write!(f, "numerical failure: {message}"),
            Error::Cancelled => write!(f, "cancelled"),
            Error::Internal(message) => write!(f, "internal failure: {message}"),
        }
    }
}

impl std::error::Error for Error {}

/// The result of every fallible function of the numerical core.
pub type Result<T> = std::result::Result<T, Error>;

/// Refuses a value that is NaN or infinite.
pub fn require_finite(field: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(field, format!("must be a finite number, got {value}")))
    }
}

/// Refuses a value that is not finite and strictly positive.
pub fn require_positive(field: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(field, format!("must be a finite positive number, got {value}")))
    }
}
