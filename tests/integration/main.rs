//! The workspace's integration tests, one binary: the `hyst` program end to end (`cli`),
//! the benchmarks' records reproduced, and the libraries checked on the shared data. One
//! binary links the libraries once (37 binaries each linked faer and instantiated its
//! generics anew). `cargo test --test integration <module>::` runs one file's tests.

mod common;

mod amplitude_chain;
mod amplitude_f16;
mod benchmark_reproduction;
mod cli;
mod covssi_data;
mod f16_levels;
mod fdd_oma;
mod floors;
mod html_report;
mod ident_benchmark;
mod measured_defaults;
mod mode_decision_corpus;
mod one_record;
mod refine_benchmark;
mod refine_loop;
mod refine_silverbox;
mod refine_synthetic;
mod screen_real_records;
mod statistical_linearization;
mod steelframe_setups;
mod track_store;
mod zener_real_pole;
