//! A tile flushes to any `DrawTarget` whose colour type it converts to, with
//! one `fill_contiguous` over the tile rectangle.

use tilerast::embedded_graphics_core::{
    draw_target::DrawTarget,
    geometry::{OriginDimensions, Size},
    pixelcolor::{BinaryColor, Gray8, PixelColor, Rgb565, Rgb888},
    primitives::Rectangle,
    Pixel,
};
use tilerast::prelude::*;

/// Records every call it gets.
struct Capture<C> {
    pixels: Vec<C>,
    rects: Vec<Rectangle>,
    single_pixel_calls: usize,
}

impl<C> Capture<C> {
    fn new() -> Self {
        Capture {
            pixels: vec![],
            rects: vec![],
            single_pixel_calls: 0,
        }
    }
}

impl<C> OriginDimensions for Capture<C> {
    fn size(&self) -> Size {
        Size::new(16, 8)
    }
}

impl<C: PixelColor> DrawTarget for Capture<C> {
    type Color = C;
    type Error = core::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<C>>>(&mut self, p: I) -> Result<(), Self::Error> {
        self.single_pixel_calls += p.into_iter().count();
        Ok(())
    }
    fn fill_contiguous<I: IntoIterator<Item = C>>(
        &mut self,
        r: &Rectangle,
        c: I,
    ) -> Result<(), Self::Error> {
        self.rects.push(*r);
        self.pixels.extend(c);
        Ok(())
    }
}

fn gradient_tile<F: PixelFormat>() -> Tile<16, Planes<F>> {
    let mut t: Tile<16, Planes<F>> = Tile::new();
    t.begin(Rect::new(0, 0, 16, 8), &Clear::default()).unwrap();
    let v = |x: i32, y: i32, c: u8| {
        Vertex::new(Coord::from_num(x), Coord::from_num(y), 0, Rgb::new(c, c, c))
    };
    t.draw(&Command::Triangle {
        v: [v(-20, -8, 0), v(40, -8, 255), v(-20, 30, 128)],
        state: State::default(),
    })
    .unwrap();
    t
}

fn check<F: PixelFormat, C: PixelColor + core::fmt::Debug + From<F::Color>>() -> Capture<C> {
    let t = gradient_tile::<F>();
    let mut target = Capture::<C>::new();
    t.flush(&mut target).unwrap();
    assert_eq!(
        target.rects,
        [Rectangle::new(Default::default(), Size::new(16, 8))]
    );
    assert_eq!(
        target.single_pixel_calls, 0,
        "one fill_contiguous, no per-pixel calls"
    );
    let expect: Vec<C> = t.colors().map(C::from).collect();
    assert_eq!(target.pixels, expect);
    target
}

#[test]
fn tiles_flush_to_other_colour_types() {
    check::<Rgb444Format, Rgb565>();
    check::<Rgb444Format, Rgb888>();
    check::<Rgb888Format, Rgb565>();
    check::<Rgb565Format, Rgb888>();
    check::<Gray8Format, Rgb565>();
    let bin = check::<Gray8Format, BinaryColor>();
    assert!(bin.pixels.contains(&BinaryColor::On) && bin.pixels.contains(&BinaryColor::Off));
    check::<BinaryFormat, Gray8>();
    check::<BinaryFormat, Rgb565>();
}
