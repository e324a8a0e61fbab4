//! hyst-monitor's integration tests, one binary: campaigns, confounded and correlated
//! records, the subspace test. `cargo test -p hyst-monitor --test integration <module>::`
//! runs one file's tests.

mod common;

mod campaign;
mod confounded;
mod correlated;
mod subspace;
