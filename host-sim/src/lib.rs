//! # tilerast-sim
//!
//! The host side of tilerast: it reads a scene file ([`scene`]), renders it
//! with the very same `no_std` core the firmware runs, tile by tile
//! ([`render`](mod@render)), writes PNGs ([`image`]), renders the same scene with an f64
//! reference rasterizer ([`reference`](mod@reference)), and measures the difference
//! ([`metrics`]). [`PngDisplay`] is a `DrawTarget` that writes PNGs, so a
//! firmware's own drawing code runs unchanged on the host.

pub mod city;
pub mod display;
pub mod error;
pub mod image;
pub mod mesh;
pub mod meshtex;
pub mod metrics;
pub mod obj;
pub mod reference;
pub mod render;
/// The deterministic PRNG, shared with the firmware workloads.
pub use tilerast_fw::rng;
pub mod scene;
pub mod silhouette;
pub mod texscene;
pub mod volume;

pub use display::PngDisplay;
pub use error::{Error, Location, Result};
pub use image::Image;
pub use obj::Limits;
pub use render::{render, render_textured, AaKind, Config, FormatKind, Rendered, TexKind};
pub use scene::Scene;
