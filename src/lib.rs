//! **hyst** — identify the stiffness and hysteretic damping of a vibrating structure from its
//! measured response.
//!
//! This crate is the command-line program `hyst` and a thin facade over the workspace:
//! [`model`] (Bouc-Wen, Zener and linear oscillators), [`sim`] (simulation, excitations,
//! resampling), [`io`] (the readers and writers of records, setups and shapes: hyst-io) and
//! [`report`] (a library report with the file it came from, as the command line prints and
//! writes it), with what the command line and the Python package share ([`settings`],
//! [`setups`], [`html`]) and the command line's campaign of record files ([`campaign`]).

pub use covssi;
pub use hyst_ident as ident;
pub use hyst_io as io;
pub use hyst_linearize as linearize;
pub use hyst_model as model;
pub use hyst_monitor as monitor;
pub use hyst_sim as sim;

pub mod campaign;
pub mod html;
pub mod report;
pub mod rigid_floors;
pub mod settings;
pub mod setups;

/// The command line's own: the figures it draws, their plotting helpers, and the campaign
/// store of `hyst track` (feature `cli`, so that the Python package builds without plotters,
/// SQLite and Parquet).
#[cfg(feature = "cli")]
pub mod figures;
#[cfg(feature = "cli")]
pub mod plot;
#[cfg(feature = "cli")]
pub mod store;

pub use covssi::shape_text;
