//! The servers' logs under test. They go through the test harness's capture (`with_test_writer`),
//! so a failing test prints what its server logged and a passing one stays quiet; the filter is
//! `WINDMETA_TEST_LOG` (default `info`).

use std::sync::Once;
use tracing_subscriber::EnvFilter;

/// Installs the subscriber once per run; every test that starts a server calls it.
pub fn capture() {
    static INSTALLED: Once = Once::new();
    INSTALLED.call_once(|| {
        let filter = EnvFilter::try_from_env("WINDMETA_TEST_LOG").unwrap_or_else(|_| EnvFilter::new("info"));
        let _ = tracing_subscriber::fmt().with_env_filter(filter).with_ansi(false).with_test_writer().try_init();
    });
}
