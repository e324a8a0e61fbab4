//! The workspace's integration tests, one binary: the `hyst` program end to end (`cli`),
//! the benchmarks' records reproduced, and the libraries checked on the shared data. One
//! binary links the libraries once (37 binaries each linked faer and instantiated its
//! generics anew). `cargo test --test integration <module>::` runs one file's tests.

mod common;

mod amplitude_f16;
mod cli;
mod covssi_data;
mod fdd_oma;
mod html_report;
mod many_channels;
mod measured_defaults;
mod mode_decision_corpus;
mod screen_real_records;
mod steelframe_setups;
mod track_follow;
mod track_store;
