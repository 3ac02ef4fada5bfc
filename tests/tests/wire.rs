//! The display-list wire format: what a firmware replays from flash is
//! exactly the scene's command list, and bad bytes are errors, not panics.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast::wire::{self, Encoded, SceneHeader};
use tilerast_sim::{render, Scene};
use tilerast_tests::{random_command, scene, Rng};

fn decode_all(bytes: &[u8]) -> Result<Vec<Command>, Error> {
    Encoded(bytes).iter().collect()
}

#[test]
fn demo_scenes_round_trip_through_flash_encoding() {
    for name in ["demo", "ssd1306"] {
        let s = Scene::load(scene(&format!("{name}.toml"))).unwrap();
        let bytes = s.encode().unwrap();
        let (h, cmds) = SceneHeader::parse(&bytes).unwrap();
        assert_eq!(h, s.header());
        assert_eq!(decode_all(cmds.0).unwrap(), s.commands, "{name}");
        // Meshes share vertices: the encoding is well below 41 bytes a triangle.
        let per_tri = bytes.len() as f64 / s.commands.len() as f64;
        assert!(per_tri < 12.0, "{name}: {per_tri:.1} bytes per command");
    }
}

#[test]
fn rendering_from_flash_equals_rendering_the_list() {
    let s = Scene::load(scene("demo.toml")).unwrap();
    let bytes = s.encode().unwrap();
    let (h, cmds) = SceneHeader::parse(&bytes).unwrap();
    let mut tile: Box<Tile<2048, Planes<Rgb444Format, Depth16, Wid8, Bayer8>>> = Box::default();
    let frame = h.frame(h.tile).unwrap();
    let mut raw = vec![0u32; 240 * 240];
    frame
        .render_with(&mut tile, &cmds, |t| {
            let a = t.area();
            for y in a.y..a.y + a.h as i32 {
                for x in a.x..a.x + a.w as i32 {
                    raw[(y * 240 + x) as usize] = t.raw(x, y).unwrap();
                }
            }
            Ok::<(), ()>(())
        })
        .unwrap();
    assert_eq!(raw, render(&s.config, &s.commands).unwrap().raw);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(64)))]
    #[test]
    fn random_commands_round_trip(seed in any::<u64>()) {
        let mut rng = Rng::new(seed);
        let cmds: Vec<Command> = (0..20).map(|_| { let w = rng.byte() % 4; random_command(&mut rng, w) }).collect();
        let mut bytes = vec![];
        for c in &cmds {
            let mut buf = [0u8; wire::MAX_ENCODED];
            let n = wire::encode(c, &mut buf).unwrap();
            bytes.extend_from_slice(&buf[..n]);
        }
        prop_assert_eq!(decode_all(&bytes).unwrap(), cmds);
    }

    #[test]
    fn truncated_or_corrupt_bytes_are_errors(seed in any::<u64>(), cut in 0usize..400, flip in 0usize..400) {
        let s = Scene::load(scene("ssd1306.toml")).unwrap();
        let bytes = s.encode().unwrap();
        let body = &bytes[wire::HEADER_LEN..];
        // Any prefix decodes to a prefix of the commands, then at most one error.
        let cut = &body[..cut.min(body.len())];
        let got: Vec<Result<Command, Error>> = Encoded(cut).iter().collect();
        let oks = got.iter().take_while(|r| r.is_ok()).count();
        prop_assert!(got.len() - oks <= 1);
        // Flipped bytes never panic; whatever decodes is valid.
        let mut bad = body[..400.min(body.len())].to_vec();
        let mut rng = Rng::new(seed);
        let i = flip % bad.len();
        bad[i] ^= rng.byte() | 1;
        for c in Encoded(&bad).iter().flatten() {
            prop_assert!(c.validate().is_ok());
        }
    }
}

#[test]
fn header_mismatch_and_garbage_are_errors() {
    assert_eq!(
        SceneHeader::parse(b"nope").map(|h| h.0),
        Err(Error::Malformed)
    );
    let s = Scene::load(scene("ssd1306.toml")).unwrap();
    let bytes = s.encode().unwrap();
    let (h, _) = SceneHeader::parse(&bytes).unwrap();
    assert!(h
        .check::<Planes<BinaryFormat, Depth16, NoWid, Bayer4>>()
        .is_ok());
    assert_eq!(
        h.check::<Planes<BinaryFormat, Depth16, NoWid, Bayer8>>(),
        Err(Error::ConfigMismatch)
    );
    assert_eq!(decode_all(&[99, 0]), Err(Error::Malformed));
    assert_eq!(decode_all(&[1, 0, 1, 2]), Err(Error::Malformed));
}

/// A screen-sized `DrawTarget` that keeps what it receives.
struct Screen(Vec<Rgb444>);

impl tilerast::embedded_graphics_core::geometry::OriginDimensions for Screen {
    fn size(&self) -> tilerast::embedded_graphics_core::geometry::Size {
        tilerast::embedded_graphics_core::geometry::Size::new(240, 240)
    }
}

impl tilerast::embedded_graphics_core::draw_target::DrawTarget for Screen {
    type Color = Rgb444;
    type Error = core::convert::Infallible;
    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = tilerast::embedded_graphics_core::Pixel<Rgb444>>,
    {
        for p in pixels {
            self.0[(p.0.y * 240 + p.0.x) as usize] = p.1;
        }
        Ok(())
    }
}

#[test]
fn text_overlay_through_the_tile_draw_target_changes_only_the_label() {
    let s = Scene::load(scene("demo.toml")).unwrap();
    let bytes = s.encode().unwrap();
    let mut tile: Box<Tile<2048, Planes<Rgb444Format, Depth16, Wid8, Bayer8>>> = Box::default();
    let mut render = |label: Option<&str>, tile_size: (u16, u16)| {
        let mut screen = Screen(vec![Rgb444::default(); 240 * 240]);
        let mut bins: Box<Bins<4096, 64>> = Box::default();
        tilerast_fw::run_scene(
            &bytes,
            &mut tile,
            &mut *bins,
            tile_size,
            label,
            &mut screen,
            &mut || 0,
        )
        .unwrap();
        screen.0
    };
    let plain = render(None, (64, 32));
    // The label spans tiles; it must come out the same whatever the tiling.
    let labelled = render(Some("tilerast"), (37, 23));
    assert_eq!(labelled, render(Some("tilerast"), (64, 32)));
    let changed: Vec<usize> = (0..plain.len())
        .filter(|&i| plain[i] != labelled[i])
        .collect();
    assert!(
        changed.len() > 50,
        "the label is drawn ({} pixels)",
        changed.len()
    );
    // 8 characters of the 6x10 font at (6, 4).
    assert!(changed
        .iter()
        .all(|&i| (6..54).contains(&(i % 240)) && (4..14).contains(&(i / 240))));
}
