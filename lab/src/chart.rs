//! Charts with `plotters`, drawn into the simulator's [`Image`] (so they
//! are written by the same PNG code as every render). Text uses the
//! DejaVu Sans font shipped in `lab/assets/` (its licence beside it), so
//! no system font library is needed on any machine.

use plotters::prelude::*;
use std::sync::Once;
use tilerast_sim::Image;

static FONT: Once = Once::new();

/// The font family name the charts use.
pub const SANS: &str = "sans-serif";

/// A `w x h` chart drawn by `draw` on a white area.
pub fn plot(
    w: u32,
    h: u32,
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<(), String>,
) -> Result<Image, String> {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        plotters::style::register_font(SANS, FontStyle::Normal, bytes)
            .unwrap_or_else(|_| panic!("the shipped font parses"));
    });
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let area = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        area.fill(&WHITE).map_err(|e| e.to_string())?;
        draw(&area)?;
        area.present().map_err(|e| e.to_string())?;
    }
    let mut img = Image::new(w, h);
    for (p, c) in img.pixels.iter_mut().zip(buf.chunks_exact(3)) {
        *p = [c[0], c[1], c[2]];
    }
    Ok(img)
}

/// The plotters error as text.
pub fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// One labelled series: a 2-pixel line through `pts` with a dot at each.
pub fn line_with_dots<'a, CT>(
    c: &mut ChartContext<'a, BitMapBackend<'a>, CT>,
    pts: Vec<(f64, f64)>,
    label: impl Into<String>,
    color: RGBColor,
) -> Result<(), String>
where
    CT: plotters::coord::CoordTranslate<From = (f64, f64)>,
{
    c.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
        .map_err(err)?
        .label(label)
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], color.stroke_width(2)));
    c.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
        .map_err(err)?;
    Ok(())
}

/// The series' legend in a framed box at `pos`.
pub fn legend<'a, CT>(
    c: &mut ChartContext<'a, BitMapBackend<'a>, CT>,
    pos: SeriesLabelPosition,
) -> Result<(), String>
where
    CT: plotters::coord::CoordTranslate<From = (f64, f64)>,
{
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((SANS, 13))
        .position(pos)
        .draw()
        .map_err(err)
}

/// Equal-sized pictures in a grid, one row of `pics` a row.
pub fn grid(pics: &[&[Image]]) -> Image {
    let (w, h) = (pics[0][0].width, pics[0][0].height);
    let cols = pics.iter().map(|r| r.len()).max().unwrap_or(0) as u32;
    let mut out = Image::new(cols * w, pics.len() as u32 * h);
    for (r, row) in pics.iter().enumerate() {
        for (c, img) in row.iter().enumerate() {
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    let o = ((r as u32 * h + y) * cols * w + c as u32 * w + x) as usize;
                    out.pixels[o] = img.pixels[i];
                }
            }
        }
    }
    out
}
