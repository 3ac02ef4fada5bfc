//! Your firmware's drawing code on the host, writing PNG files: a
//! [`PngDisplay`] is an `embedded-graphics` `DrawTarget` of any colour type
//! that keeps its pixels and saves them as a PNG, and [`Image`] reads and
//! writes 8-bit RGB PNGs with every allocation bounded before it is made.
//!
//! This crate depends on `embedded-graphics-core` and `png` alone, so it
//! builds in seconds: a firmware author's host test of
//! `renderer.draw(&list, &mut display)` needs nothing else. The
//! simulator (`tilerast-sim`: scene files, the f64 reference, reports)
//! re-exports both types.
//!
//! ```
//! use embedded_graphics_core::{pixelcolor::Rgb565, prelude::*, primitives::Rectangle};
//! use tilerast_png::PngDisplay;
//!
//! let mut display = PngDisplay::<Rgb565>::new(64, 48);
//! display.fill_solid(&Rectangle::new(Point::new(2, 2), Size::new(10, 4)), Rgb565::RED)?;
//! assert_eq!(display.image().get(5, 3), [255, 0, 0]);
//! # let path = std::env::temp_dir().join("tilerast-png-lib-doc.png");
//! display.save_png(&path)?; // look at it
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]
#![deny(missing_docs)]

use embedded_graphics_core::{
    draw_target::DrawTarget,
    geometry::{OriginDimensions, Size},
    pixelcolor::{PixelColor, Rgb888, RgbColor},
    Pixel,
};
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Seek};
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

/// The largest side [`Image::load_png`] accepts by default, in pixels: a
/// texture on a small display needs far less, and 4096 x 4096 RGBA is 64 MB
/// decoded.
pub const MAX_SIDE: u32 = 4096;

/// What went wrong reading or writing a PNG.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be opened, created, read or written.
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The PNG codec refused the data.
    Png {
        /// The file.
        path: PathBuf,
        /// What is wrong, in words.
        message: String,
    },
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Error::Png { path, message } => write!(f, "{}: {message}", path.display()),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            Error::Png { .. } => None,
        }
    }
}

/// An 8-bit RGB image, row-major.
#[derive(Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels.
    pub pixels: Vec<[u8; 3]>,
}

impl std::fmt::Debug for Image {
    /// The size, not the pixels.
    ///
    /// ```
    /// assert_eq!(format!("{:?}", tilerast_png::Image::new(3, 2)), "Image { width: 3, height: 2, .. }");
    /// ```
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Image")
            .field("width", &self.width)
            .field("height", &self.height)
            .finish_non_exhaustive()
    }
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            pixels: vec![[0; 3]; width as usize * height as usize],
        }
    }

    /// The pixel at `(x, y)`.
    ///
    /// # Panics
    /// Outside the image.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "({x}, {y}) outside the image"
        );
        self.pixels[(y * self.width + x) as usize]
    }

    /// Writes an 8-bit RGB PNG.
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), Error> {
        let path = path.as_ref();
        let file = File::create(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut enc = png::Encoder::new(BufWriter::new(file), self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let png = |e: png::EncodingError| Error::Png {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut w = enc.write_header().map_err(png)?;
        w.write_image_data(self.pixels.as_flattened()).map_err(png)
    }

    /// Writes `frames` (all of `frames[0]`'s size) as an animated PNG
    /// that loops forever, each frame shown for `delay_ms` milliseconds.
    ///
    /// ```
    /// use tilerast_png::Image;
    /// let frames = [Image::new(8, 8), Image::new(8, 8)];
    /// let path = std::env::temp_dir().join("tilerast-png-anim-doc.png");
    /// Image::save_animation(&path, &frames, 40)?;
    /// assert_eq!(Image::load_png(&path)?.width, 8); // the first frame
    /// # Ok::<(), tilerast_png::Error>(())
    /// ```
    pub fn save_animation(
        path: impl AsRef<Path>,
        frames: &[Image],
        delay_ms: u16,
    ) -> Result<(), Error> {
        let path = path.as_ref();
        let png = |message: String| Error::Png {
            path: path.to_path_buf(),
            message,
        };
        let first = frames.first().ok_or_else(|| png("no frames".into()))?;
        if let Some(f) = frames
            .iter()
            .find(|f| (f.width, f.height) != (first.width, first.height))
        {
            return Err(png(format!(
                "a {} x {} frame in a {} x {} animation",
                f.width, f.height, first.width, first.height
            )));
        }
        let file = File::create(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut enc = png::Encoder::new(BufWriter::new(file), first.width, first.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let codec = |e: png::EncodingError| png(e.to_string());
        enc.set_animated(frames.len() as u32, 0).map_err(codec)?;
        enc.set_frame_delay(delay_ms, 1000).map_err(codec)?;
        let mut w = enc.write_header().map_err(codec)?;
        for f in frames {
            w.write_image_data(f.pixels.as_flattened()).map_err(codec)?;
        }
        w.finish().map_err(codec)
    }

    /// Reads an 8-bit RGB, RGBA, grey or grey-alpha PNG (alpha is
    /// dropped, 16-bit channels are cut to 8) of at most [`MAX_SIDE`]
    /// pixels a side.
    pub fn load_png(path: impl AsRef<Path>) -> Result<Self, Error> {
        Self::load_png_within(path, MAX_SIDE)
    }

    /// [`Image::load_png`] of at most `max_side` pixels a side. The
    /// header's size is checked before anything is decoded or allocated:
    /// a 16 KB file that claims 65535 x 65535 pixels is an error, not a
    /// 17 GB allocation.
    ///
    /// ```
    /// use tilerast_png::Image;
    /// let path = std::env::temp_dir().join("tilerast-png-within-doc.png");
    /// Image::new(40, 30).save_png(&path)?;
    /// assert_eq!(Image::load_png_within(&path, 64)?.width, 40);
    /// let e = Image::load_png_within(&path, 32).unwrap_err();
    /// assert!(e.to_string().ends_with("40 x 30 pixels: larger than the limit of 32 a side"));
    /// # Ok::<(), tilerast_png::Error>(())
    /// ```
    pub fn load_png_within(path: impl AsRef<Path>, max_side: u32) -> Result<Self, Error> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::decode(BufReader::new(file), max_side).map_err(|message| Error::Png {
            path: path.to_path_buf(),
            message,
        })
    }

    /// Decodes a PNG from `input` of at most `max_side` pixels a side;
    /// the error in words.
    ///
    /// ```
    /// let bytes = std::io::Cursor::new(b"\x89PNG\r\n\x1a\n");
    /// let e = tilerast_png::Image::decode(bytes, 64).unwrap_err();
    /// assert_eq!(e, "not a PNG, or a truncated one: the data ends early");
    /// ```
    pub fn decode(input: impl BufRead + Seek, max_side: u32) -> Result<Self, String> {
        let mut dec = png::Decoder::new(input);
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut reader = dec.read_info().map_err(|e| describe(&e))?;
        let (w, h) = reader.info().size();
        if w > max_side || h > max_side {
            return Err(format!(
                "{w} x {h} pixels: larger than the limit of {max_side} a side"
            ));
        }
        let len = reader
            .output_buffer_size()
            .ok_or_else(|| format!("{w} x {h} pixels: too large to decode"))?;
        let mut buf = vec![0; len];
        let info = reader.next_frame(&mut buf).map_err(|e| describe(&e))?;
        let ch = match info.color_type {
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Indexed => return Err("an indexed PNG that did not expand".into()),
        };
        let pixels = buf[..info.buffer_size()]
            .chunks_exact(ch)
            .map(|p| {
                if ch >= 3 {
                    [p[0], p[1], p[2]]
                } else {
                    [p[0]; 3]
                }
            })
            .collect();
        Ok(Image {
            width: info.width,
            height: info.height,
            pixels,
        })
    }
}

/// A decoder error in words.
fn describe(e: &png::DecodingError) -> String {
    match e {
        png::DecodingError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "not a PNG, or a truncated one: the data ends early".into()
        }
        png::DecodingError::IoError(io) => format!("read error: {io}"),
        png::DecodingError::Format(f) => format!("malformed PNG: {f}"),
        png::DecodingError::LimitsExceeded => "the PNG exceeds the decoder's memory limit".into(),
        other => other.to_string(),
    }
}

/// A `width x height` display of colour type `C` (`Rgb565`, `BinaryColor`,
/// `Gray8`, ...) held as RGB888; pixels outside it are ignored, as a panel
/// does.
///
/// ```
/// use embedded_graphics_core::{pixelcolor::BinaryColor, prelude::*};
/// let mut oled = tilerast_png::PngDisplay::<BinaryColor>::new(128, 64);
/// oled.draw_iter([Pixel(Point::new(3, 4), BinaryColor::On), Pixel(Point::new(500, 4), BinaryColor::On)])?;
/// assert_eq!(oled.image().get(3, 4), [255, 255, 255]);
/// # Ok::<(), core::convert::Infallible>(())
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
    pub fn save_png(&self, path: impl AsRef<Path>) -> Result<(), Error> {
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
