//! A display on the host: [`tilerast_png::PngDisplay`], an
//! `embedded-graphics` `DrawTarget` that keeps the pixels and writes them to
//! a PNG, so the drawing code of a firmware —
//! `renderer.draw(&list, &mut display)`, text, primitives — runs unchanged
//! on the host, as `embedded-graphics`' own simulator does. It lives in the
//! light crate `tilerast-png` (seconds to build); the simulator re-exports
//! it.
//!
//! ```
//! use embedded_graphics_core::pixelcolor::Rgb565;
//! use tilerast::prelude::*;
//! use tilerast_sim::PngDisplay;
//!
//! // The firmware's drawing code, unchanged:
//! let mut renderer: Renderer<St7789Config, { groups(32, 32) }> = Renderer::new(64, 48)?;
//! let list = [Command::triangle([
//!     Vertex::px(2, 2, 0, Rgb::new(255, 0, 0)),
//!     Vertex::px(60, 8, 0, Rgb::new(0, 255, 0)),
//!     Vertex::px(20, 46, 0, Rgb::new(0, 0, 255)),
//! ])];
//! let mut display = PngDisplay::<Rgb565>::new(64, 48);
//! renderer.draw(&list[..], &mut display)?;
//! assert_ne!(display.image().get(20, 20), [0, 0, 0]);
//! # let path = std::env::temp_dir().join("tilerast-png-display-doc.png");
//! display.save_png(&path)?; // look at it
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub use tilerast_png::PngDisplay;
