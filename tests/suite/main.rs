//! windmeta's integration tests, one binary: the physics against closed forms and independent
//! estimates, the metamodel end to end, the commands through the real binary, the service as a
//! real server on port 0 against real databases, several replicas on PostgreSQL, the contract, and
//! the page in a real Chromium. `WINDMETA_TEST_LOG=debug` (or any tracing filter) sets what the
//! servers under test log; a failing test shows its servers' logs, and `-- --nocapture` every log.

mod harness;

mod api;
mod browser;
mod cancellation;
mod certify;
mod cli;
mod design;
mod dynamics;
mod edge;
mod metamodel;
mod openapi;
mod replicas;
mod wind;
