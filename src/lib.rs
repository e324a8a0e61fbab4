//! **hyst** — identify the stiffness and hysteretic damping of a vibrating structure from its
//! measured response.
//!
//! This crate is the command-line program `hyst` and a thin facade over the workspace:
//! [`model`] (Bouc-Wen, Zener and linear oscillators), [`sim`] (simulation, excitations,
//! resampling), [`io`] (CSV records and the shared data folder) and [`report`] (a library
//! report with the file it came from, as the command line prints and writes it).

pub use covssi;
pub use hyst_ident as ident;
pub use hyst_linearize as linearize;
pub use hyst_model as model;
pub use hyst_monitor as monitor;
pub use hyst_sim as sim;

pub mod figures;
pub mod html;
pub mod io;
pub mod plot;

pub mod report;
pub mod settings;
pub mod setups;
pub mod store;

pub use covssi::shape_text;
