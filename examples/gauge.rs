//! A gauge whose needle moves: with partial updates the renderer draws and
//! sends only the tiles whose commands changed since the last frame (the
//! panel's memory keeps the rest). Prints the tiles sent a frame and writes
//! the last frame to `gauge.png`.
//!
//! `cargo run --example gauge` (add `-- out.png` for another file).

use embedded_graphics_core::pixelcolor::Rgb565;
use tilerast::prelude::*;
use tilerast_png::PngDisplay;

/// The gauge at `value` (0..=100): a dial and a needle from its centre.
fn gauge(value: i32) -> Result<DisplayList<4>, Error> {
    let mut list = DisplayList::new();
    list.push(Command::fill(Rect::new(0, 0, 240, 240), Rgb::new(0, 0, 0)))?;
    list.push(Command::fill(
        Rect::new(20, 20, 200, 200),
        Rgb::new(30, 30, 50),
    ))?;
    // The needle: a thin triangle from the centre towards the value's angle.
    let a = (value as f32 / 100.0 * 270.0 - 225.0).to_radians();
    let (c, s) = (a.cos(), a.sin());
    let tip = Vertex::try_from_f32(120.0 + 90.0 * c, 120.0 + 90.0 * s, 0, Rgb::new(255, 80, 0))?;
    let l = Vertex::try_from_f32(120.0 - 6.0 * s, 120.0 + 6.0 * c, 0, Rgb::new(255, 200, 0))?;
    let r = Vertex::try_from_f32(120.0 + 6.0 * s, 120.0 - 6.0 * c, 0, Rgb::new(255, 200, 0))?;
    list.push(Command::triangle([l, tip, r]))?;
    Ok(list)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "gauge.png".into());
    let mut renderer: Renderer<St7789Config, { groups(40, 40) }> =
        Renderer::with_tile(240, 240, 40, 40)?.with_partial_updates(true);
    let mut display = PngDisplay::<Rgb565>::new(240, 240);
    let total = renderer.frame().tiles().count();
    for value in [0, 0, 5, 10, 10, 50] {
        let list = gauge(value)?;
        let mut sent = 0;
        renderer.render(&list, |tile| {
            sent += 1;
            tile.flush(&mut display)
        })?;
        println!("value {value:3}: {sent:2} of {total} tiles drawn and sent");
    }
    display.save_png(&out)?;
    println!("{out}");
    Ok(())
}
