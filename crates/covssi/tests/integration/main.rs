//! covssi's integration tests, one binary (one link of faer, its generics instantiated
//! once): exact records, bad input, FDD, the jackknife, the merge of setups, properties and
//! serde. `cargo test -p covssi --test integration <module>::` runs one file's tests.

mod bad_input;
mod exact;
mod fdd;
mod jackknife;
mod multisetup;
mod properties;
mod serde;
