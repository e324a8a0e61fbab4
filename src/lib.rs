//! **hyst** — identify the stiffness and hysteretic damping of a vibrating structure from its
//! measured response.
//!
//! This crate is the command-line program `hyst` and a thin facade over the workspace:
//! [`model`] (Bouc-Wen, Zener and linear oscillators), [`sim`] (simulation, excitations,
//! resampling) and [`io`] (CSV records and the shared data folder).

pub use covssi;
pub use hyst_ident as ident;
pub use hyst_linearize as linearize;
pub use hyst_model as model;
pub use hyst_sim as sim;

pub mod io;
pub mod plot;

/// A mode shape as "magnitude∠phase°" per entry (phase rounded to a degree), entries joined
/// by `sep`: how `hyst ssi`, `hyst frf` and `cargo xtask f16` print shapes.
pub fn shape_text(shape: &[covssi::Complex64], sep: &str) -> String {
    shape
        .iter()
        .map(|v| {
            // + 0.0 turns a rounded −0 into 0.
            let deg = v.arg().to_degrees().round() + 0.0;
            format!("{:.3}∠{deg:.0}°", v.norm())
        })
        .collect::<Vec<_>>()
        .join(sep)
}
