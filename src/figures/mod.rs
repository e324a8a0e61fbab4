//! The figures the commands draw (SVG through [`crate::plot`]), one module per command;
//! each function draws every figure of its command into a folder.

mod amplitude;
mod ident;
mod levels;
mod loops;
mod residual;
mod track;

pub use amplitude::{MODEL_SUFFIX, amplitude_svg};
pub use ident::ident_figures;
pub use levels::levels_figures;
pub use residual::residual_figures;
pub use track::track_figures;
