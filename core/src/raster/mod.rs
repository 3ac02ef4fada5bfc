//! Rasterization (pipeline stage 4): turning a set-up primitive into
//! fragments, with exact integer arithmetic so tiling cannot change a
//! pixel.
//!
//! - `traverse`: the rows of a triangle, exact per-row coverage with the
//!   top-left fill rule (seed 001 §III: triangle input to the span engine);
//! - `span`: the span DDA values every primitive ends in (seed 001 §II.1);
//! - [`line`]: Bresenham and two-point (Wu) lines, antialiased solid edges
//!   (seed 003 eqs. 4, 7, 8);
//! - `texmap`: texture coordinates along a span, affine, quadratic (the
//!   RE's) or divided per pixel (seed 001 §IV.3);
//! - [`area`]: exact pixel coverage by a triangle's flagged edges, the
//!   RE's area-sampling antialiasing through the α-channel (seed 001 §IV.5);
//! - [`coverage`]: sample patterns, coverage masks and the RUF buffer
//!   (seed 000 eqs. 1-3, 6, 7).
//!
//! The fragments go on to the fragment stage ([`crate::fragment`]) through
//! the tile's drawing code ([`crate::tile`]).

pub mod area;
pub mod coverage;
pub mod line;
pub(crate) mod span;
pub(crate) mod texmap;
pub(crate) mod traverse;
