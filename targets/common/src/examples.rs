//! What the real-board examples draw, frame by frame: one source for their
//! firmware and for the host, which renders the same frames and checks the
//! emulated RP2040's panels against them byte for byte
//! (`tests/tests/rp2040.rs`).
//!
//! - [`cube`]: the ST7789 examples (`targets/rp-pico-st7789`,
//!   `rp-pico2-st7789`, `esp32c3-st7789`): a lit cube turned by the geometry
//!   stage, 240x240 in 60x40 tiles of the ST7789 preset.
//! - [`oled`]: the SSD1306 example (`targets/rp-pico-ssd1306`): a spinning
//!   shaded triangle over a grey ramp and a label, the 128x64 screen one
//!   tile of the SSD1306 preset.

/// The ST7789 examples' turning cube.
pub mod cube {
    use tilerast::geometry::{Angle, DrawOptions, Lighting, Mat4, Mesh, Real, Scene};
    use tilerast::prelude::*;

    /// The renderer: 60x40-pixel tiles of the ST7789 preset (RGB565 +
    /// 16-bit Z + 4x4 dither, 9.6 KB), bins and state with their defaults.
    pub type Panel = Renderer<St7789Config, { groups(60, 40) }>;

    /// Screen side, pixels.
    pub const SIDE: u16 = 240;
    /// Tile size, pixels: a window the panel takes per DMA transfer.
    pub const TILE: (u16, u16) = (60, 40);
    /// Bytes of one tile as the panel takes it (RGB565).
    pub const TILE_BYTES: usize = TILE.0 as usize * TILE.1 as usize * 2;
    /// What each frame turns the cube by.
    pub const STEP: Angle = Angle::degrees(3);

    /// The renderer, cleared to a dark blue.
    pub fn renderer() -> Result<Panel, Error> {
        Ok(
            Panel::with_tile(SIDE, SIDE, TILE.0, TILE.1)?.with_clear(Clear {
                color: Rgb::new(8, 8, 16),
                ..Clear::default()
            }),
        )
    }

    /// The camera 3 units away, 40° field of view, a 240x240 viewport, and
    /// one white light from the upper left: set once.
    pub fn camera<S: Real>(scene: &mut Scene<'_, S>) -> Result<(), Error> {
        let q = |v: i32| S::from_q(v as i64, 8); // 1/256 units
        scene.set_camera(
            Mat4::look_at([q(0), q(0), q(3 * 256)], [q(0); 3], [q(0), q(256), q(0)])?,
            Mat4::perspective(Angle::degrees(40), S::ONE, q(256), q(5 * 256))?,
        );
        scene.set_viewport(Rect::new(0, 0, SIDE as u32, SIDE as u32))?;
        scene.set_lighting(Lighting::white([q(-102), q(154), q(256)], q(51))?);
        Ok(())
    }

    /// This frame's draw: `mesh` turned by `t` about y and half that about x.
    pub fn turn<'a, S: Real>(
        scene: &mut Scene<'a, S>,
        mesh: &Mesh<'a>,
        t: Angle,
    ) -> Result<(), Error> {
        scene.clear();
        let half = Angle::from_turn_q16(t.turn_q16() / 2);
        let model = Mat4::rotation_x(half).mul(&Mat4::rotation_y(t));
        scene.draw(mesh, &model, &DrawOptions::default())?;
        Ok(())
    }
}

/// The SSD1306 example's triangle and label.
pub mod oled {
    use embedded_graphics::{
        mono_font::{ascii::FONT_6X10, MonoTextStyle},
        pixelcolor::BinaryColor,
        prelude::*,
        text::Text,
    };
    use micromath::F32Ext;
    use tilerast::prelude::*;

    /// The renderer: the whole 128x64 screen as one tile of the SSD1306
    /// preset (1 KB), bins and state with their defaults.
    pub type Oled = Renderer<Ssd1306Config, { groups(128, 64) }>;

    /// What each frame turns the triangle by, radians.
    pub const STEP: f32 = 0.05;

    /// The renderer: one tile covers the screen.
    pub fn renderer() -> Result<Oled, Error> {
        Oled::new(128, 64)
    }

    /// A spinning shaded triangle at `angle` over a grey ramp (the dither
    /// shows both). Setup-time float math (soft float on a Cortex-M0+),
    /// never per pixel. Sine and cosine are `micromath`'s, called by path:
    /// on a host `a.cos()` is `std`'s and rounds differently, so the host's
    /// frames drifted from the board's (the emulated RP2040 showed it).
    pub fn scene(list: &mut DisplayList<3>, angle: f32) -> Result<(), Error> {
        list.clear();
        let v = |x: f32, y: f32, l: u8| Vertex::try_from_f32(x, y, 0, Rgb::new(l, l, l));
        list.push(Command::triangle([
            v(0.0, 64.0, 0)?,
            v(128.0, 64.0, 90)?,
            v(0.0, 40.0, 30)?,
        ]))?;
        list.push(Command::triangle([
            v(128.0, 64.0, 90)?,
            v(128.0, 40.0, 60)?,
            v(0.0, 40.0, 30)?,
        ]))?;
        let corner = |k: f32| {
            let a = angle + k * 2.094_395;
            (64.0 + 28.0 * F32Ext::cos(a), 34.0 + 28.0 * F32Ext::sin(a))
        };
        let [(x0, y0), (x1, y1), (x2, y2)] = [corner(0.0), corner(1.0), corner(2.0)];
        list.push(Command::triangle([
            v(x0, y0, 255)?,
            v(x1, y1, 120)?,
            v(x2, y2, 20)?,
        ]))
    }

    /// The label drawn over the tile before it is sent.
    pub fn label<D: DrawTarget<Color = BinaryColor>>(target: &mut D) -> Result<(), D::Error> {
        let style = MonoTextStyle::new(&FONT_6X10, BinaryColor::On);
        Text::new("tilerast", Point::new(2, 9), style).draw(target)?;
        Ok(())
    }
}
