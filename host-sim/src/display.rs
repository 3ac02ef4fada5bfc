//! A display on the host: an `embedded-graphics` `DrawTarget` that keeps
//! the pixels and writes them to a PNG, so the drawing code of a firmware —
//! `frame.render(&mut tile, &list, &mut display)`, text, primitives — runs
//! unchanged on the host, as `embedded-graphics`' own simulator does.

use crate::image::Image;
use embedded_graphics_core::{
    draw_target::DrawTarget,
    geometry::{OriginDimensions, Size},
    pixelcolor::{PixelColor, Rgb888, RgbColor},
    Pixel,
};
use std::marker::PhantomData;
use std::path::Path;

/// A `width x height` display of colour type `C` (`Rgb565`, `BinaryColor`,
/// `Gray8`, ...) held as RGB888; pixels outside it are ignored, as a panel
/// does.
///
/// ```
/// use embedded_graphics_core::pixelcolor::Rgb565;
/// use tilerast::prelude::*;
/// use tilerast_sim::PngDisplay;
///
/// // The firmware's drawing code, unchanged:
/// type PanelTile = Tile<{ groups(32, 32) }, St7789Config>;
/// let frame = PanelTile::frame::<32, 32>(64, 48)?;
/// let mut tile = PanelTile::new();
/// let v = |x: i32, y: i32, c: Rgb| Vertex::new(Coord::from_num(x), Coord::from_num(y), 0, c);
/// let list = [Command::triangle([v(2, 2, Rgb::new(255, 0, 0)), v(60, 8, Rgb::new(0, 255, 0)), v(20, 46, Rgb::new(0, 0, 255))])];
///
/// let mut display = PngDisplay::<Rgb565>::new(64, 48);
/// frame.render(&mut tile, &list[..], &mut display)?;
/// assert_ne!(display.image().get(20, 20), [0, 0, 0]);
/// # let path = std::env::temp_dir().join("tilerast-png-display-doc.png");
/// display.save_png(&path).unwrap(); // look at it
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct PngDisplay<C> {
    image: Image,
    _color: PhantomData<C>,
}

impl<C> PngDisplay<C> {
    /// A black display.
    pub fn new(width: u32, height: u32) -> Self {
        PngDisplay {
            image: Image::new(width, height),
            _color: PhantomData,
        }
    }

    /// What the display shows.
    pub fn image(&self) -> &Image {
        &self.image
    }

    /// Writes what the display shows to a PNG.
    pub fn save_png(&self, path: impl AsRef<Path>) -> crate::Result<()> {
        self.image.save_png(path)
    }
}

impl<C> OriginDimensions for PngDisplay<C> {
    fn size(&self) -> Size {
        Size::new(self.image.width, self.image.height)
    }
}

impl<C: PixelColor + Into<Rgb888>> DrawTarget for PngDisplay<C> {
    type Color = C;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<C>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        let (w, h) = (self.image.width as i32, self.image.height as i32);
        for Pixel(p, c) in pixels {
            if (0..w).contains(&p.x) && (0..h).contains(&p.y) {
                let c: Rgb888 = c.into();
                self.image.pixels[(p.y * w + p.x) as usize] = [c.r(), c.g(), c.b()];
            }
        }
        Ok(())
    }
}
