//! What the suite's tests share: the service under test ([`app`]), the metamodel every test that
//! only needs one samples ([`fixture`]), the test databases ([`postgres`]), the server's logs
//! ([`logs`]), a database outage on demand ([`proxy`]), spectral estimates of simulated series
//! ([`spectra`]), and the one way a test that cannot run says so ([`unavailable`]).

pub mod app;
pub mod fixture;
pub mod logs;
pub mod postgres;
pub mod proxy;
pub mod spectra;

use std::io::Write;

/// A test that cannot run here (no PostgreSQL, no browser) fails when `required_by` is set to 1
/// (CI sets it: there the service always runs), and otherwise says so on the process's stderr,
/// which the harness does not capture, so that the skip is seen in the run's output.
pub fn unavailable(required_by: &str, why: &str) {
    assert!(std::env::var(required_by).as_deref() != Ok("1"), "{why} ({required_by}=1 requires it)");
    let _ = writeln!(std::io::stderr(), "SKIPPED: {why}; set {required_by}=1 to make this a failure");
}
