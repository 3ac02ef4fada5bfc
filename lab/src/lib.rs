//! # tilerast-lab
//!
//! The research side of tilerast, kept out of the simulator's dependency
//! tree: reproductions of the seed papers' measurements and the sweeps that
//! put every knob on both axes, error and cost.
//!
//! - [`aa`]: every antialiasing mode and its peers (`embedded-graphics`,
//!   `tiny-skia`) against the 16x16 supersampled ideal (seeds 003, 000);
//! - [`ruf`]: the RUF-buffer paper's Tables 1-4 on its models (seed 000);
//! - [`tradeoff`]: the speed-against-accuracy sweep of every knob, with
//!   Pareto fronts;
//! - [`phong`]: fast Phong, its Taylor variant and Gouraud against exact
//!   Phong (seed 001 §IV.2);
//! - [`texture`]: affine, quadratic and exact perspective texturing
//!   against the f64 mapping, by depth ratio (seed 001 §IV.3);
//! - [`cull`]: occlusion culling (seed 004), the single pass against
//!   stop-and-wait and CHC queries on the same city walks;
//! - [`frames`]: whole frames (tiled, one tile, f64 reference) and filled
//!   triangles against `embedded-graphics` and `tiny-skia`, timed in one run.
//!
//! `tilerast-lab aa-report | ruf-report | tradeoff` writes the reports
//! into `reports/`; `cargo xtask bench` runs them all after the criterion
//! benchmark (`benches/raster.rs`).

pub mod aa;
pub mod chart;
pub mod cull;
pub mod frames;
pub mod phong;
pub mod ruf;
pub mod texture;
pub mod tradeoff;
pub mod volume;
