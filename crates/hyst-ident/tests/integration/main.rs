//! hyst-ident's integration tests, one binary: the paper's pipeline on the benchmark and
//! synthetic records, the residual loop, the levels' fits, the amplitude curves, and the
//! reports' JSON form. `cargo test -p hyst-ident --test integration <module>::` runs one
//! file's tests.

mod common;

mod amplitude_chain;
mod benchmark_reproduction;
mod f16_levels;
mod floors;
mod ident_benchmark;
mod one_record;
mod refine_benchmark;
mod refine_loop;
mod refine_silverbox;
mod refine_synthetic;
mod serde;
mod statistical_linearization;
mod storeys;
mod zener_real_pole;
