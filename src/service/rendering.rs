//! How a synchronous answer is sent: JSON, CSV or SVG, by the request's `Accept`. Each answer
//! renders itself (`ExceedanceAnswer::render`, `AnalysisAnswer::render`).

/// How a synchronous answer is sent, by `Accept`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rendering {
    Json,
    Csv,
    Svg,
}

impl Rendering {
    pub fn from_accept(accept: &str) -> Rendering {
        if accept.contains("text/csv") {
            Rendering::Csv
        } else if accept.contains("image/svg+xml") {
            Rendering::Svg
        } else {
            Rendering::Json
        }
    }
}
