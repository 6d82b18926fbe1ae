//! Pagination of lists.

use crate::service::error::ApiError;

/// Pagination of lists: `?limit=&offset=`.
#[derive(Debug, serde::Deserialize, utoipa::IntoParams)]
#[into_params(parameter_in = Query)]
pub struct Page {
    /// Items per page, 1 to 500.
    #[serde(default = "default_limit")]
    #[param(minimum = 1, maximum = 500, default = 50)]
    pub limit: i64,
    /// Items to skip.
    #[serde(default)]
    #[param(minimum = 0, default = 0)]
    pub offset: i64,
}

fn default_limit() -> i64 {
    50
}

impl Page {
    pub fn check(&self) -> Result<(), ApiError> {
        if !(1..=500).contains(&self.limit) {
            return Err(crate::error::Error::invalid("limit", "must be between 1 and 500").into());
        }
        if self.offset < 0 {
            return Err(crate::error::Error::invalid("offset", "must not be negative").into());
        }
        Ok(())
    }
}
