//! A lit cube turning, written to `spin.png` (an animated PNG): the
//! geometry stage on the host exactly as on a chip — a mesh, a camera, a
//! light, a rotation a frame — rendered by one `Renderer` in 60x40-pixel
//! tiles into a `PngDisplay`.
//!
//! `cargo run --example spin` (add `-- out.png` for another file).

use embedded_graphics_core::pixelcolor::Rgb565;
use tilerast::geometry::{Angle, DrawOptions, Lighting, Mat4, Mesh, Scene, VertexSlot, CUBE_BYTES};
use tilerast::prelude::*;
use tilerast_png::{Image, PngDisplay};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "spin.png".into());
    // The mesh a firmware reads from flash (`Mesh::parse(include_bytes!(..))`).
    let mut buf = [0u8; CUBE_BYTES];
    let cube = Mesh::cube(&mut buf)?;
    // The vertex cache: one slot a vertex of the meshes drawn.
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
    scene.set_camera(
        Mat4::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])?,
        Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 5.0)?,
    );
    scene.set_viewport(Rect::new(0, 0, 240, 240))?;
    scene.set_lighting(Lighting::white([-0.4, 0.6, 1.0], 0.2)?);

    let mut renderer: Renderer<St7789Config, { groups(60, 40) }> = Renderer::new(240, 240)?
        .with_clear(Clear {
            color: Rgb::new(8, 8, 24),
            ..Clear::default()
        });
    let mut frames = Vec::new();
    for step in 0..36 {
        let t = Angle::degrees(10 * step);
        let model = Mat4::rotation_x(Angle::degrees(5 * step)).mul(&Mat4::rotation_y(t));
        scene.clear();
        scene.draw(&cube, &model, &DrawOptions::default())?;
        let mut display = PngDisplay::<Rgb565>::new(240, 240);
        renderer.draw(&scene, &mut display)?;
        frames.push(display.image().clone());
    }
    Image::save_animation(&out, &frames, 40)?;
    println!(
        "{out}: {} frames of 240x240, {} bytes of renderer",
        frames.len(),
        Renderer::<St7789Config, { groups(60, 40) }>::BYTES
    );
    Ok(())
}
