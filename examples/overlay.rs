//! Text over rasterized content, written to `overlay.png`: each finished
//! tile gets `embedded-graphics` text drawn on it (clipped to the tile)
//! before it is flushed, so the text costs no frame buffer either.
//!
//! `cargo run --example overlay` (add `-- out.png` for another file).

use embedded_graphics::{
    mono_font::{ascii::FONT_6X10, MonoTextStyle},
    pixelcolor::{Rgb565, RgbColor},
    prelude::*,
    text::Text,
};
use tilerast::prelude::*;
use tilerast_png::PngDisplay;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "overlay.png".into());
    let mut renderer: Renderer<St7789Config, { groups(60, 40) }> = Renderer::new(240, 135)?;
    let mut list: DisplayList<3> = DisplayList::new();
    list.push(Command::fill(
        Rect::new(0, 0, 240, 135),
        Rgb::new(16, 16, 40),
    ))?;
    list.push(Command::triangle([
        Vertex::px(10, 120, 200, Rgb::new(255, 60, 0)),
        Vertex::px(120, 8, 200, Rgb::new(255, 220, 0)),
        Vertex::px(230, 120, 200, Rgb::new(200, 0, 120)),
    ]))?;
    let mut display = PngDisplay::<Rgb565>::new(240, 135);
    let style = MonoTextStyle::new(&FONT_6X10, Rgb565::WHITE);
    let stats = renderer.render(&list, |tile| {
        // A tile is a `DrawTarget`: the text lands on the pixels it covers.
        let Ok(_) = Text::new("tilerast: 8 KB a tile", Point::new(8, 128), style).draw(tile);
        tile.flush(&mut display)
    })?;
    display.save_png(&out)?;
    println!("{out}: {} tiles", stats.tiles);
    Ok(())
}
