//! Texture mapping (seed 001 §IV.3): texel reads in every format, size and
//! addressing against the f64 sampler; the three perspective modes against
//! the exact f64 mapping (`tilerast_sim::reference::render_textured`) on
//! the ramp workload (`tilerast_sim::texscene`), which reads texel error
//! off the pixels.
//!
//! **Bounds.** A texel read at 32.32 coordinates: nearest is exact (the
//! same texel as f64's floor); bilinear truncates each fraction to 8 bits
//! (moving a weight by under 1/256 of the two texels' difference, once per
//! axis) and rounds once (0.5). The exact mode's coordinates are `s / q`
//! with 24 fraction bits of a texel (a truncating division of exact
//! integers; the weights' 30 bits add under 2^-20), so on the ramp (16 per
//! texel, difference 16) a pixel is within `0.5 + 2 · 16/256 + 2^-4` LSB of
//! the f64 value: [`EXACT_LSB`]. The affine and quadratic modes are
//! approximations: measured, and held to the targets.

use proptest::prelude::*;
use tilerast::prelude::*;
use tilerast_sim::reference;
use tilerast_sim::texscene::{ramp, ramp_texels, texel_error, tilted_quad, TexelError};
use tilerast_sim::{render_textured, Config, FormatKind, TexKind};
use tilerast_tests::config;

/// Largest channel error of an exact-mode ramp pixel, 8-bit units.
const EXACT_LSB: f64 = 0.5 + 2.0 * 16.0 / 256.0 + 1.0 / 16.0;

fn cfg(w: u16, h: u16, tile: (u16, u16)) -> Config {
    let mut c = config(w, h, FormatKind::Rgb888);
    c.depth = true;
    c.tile = tile;
    c
}

/// Texel error of `kind` on `cmds` with `textures`, and the rendering.
fn error(c: &Config, cmds: &[Command], tex: &[Texture<'_>], kind: TexKind) -> TexelError {
    let ours = render_textured(c, cmds, tex, kind, 0).unwrap();
    let exact = reference::render_textured(c, cmds, tex);
    // Coverage is the Gouraud triangle's, whatever the mode.
    for (i, d) in ours.depth.iter().enumerate() {
        assert_eq!(*d < u16::MAX, exact.depth[i] < 65535.0, "coverage at {i}");
    }
    texel_error(&ours, &exact)
}

/// The tilted rectangle at depth ratios 1..64 on a 240x240 display (spans
/// up to 216 pixels): the target — quadratic within half a texel
/// wherever affine is off by more than two (from ratio 16 on only because
/// segments split where the depth changes fast) — and the exact mode
/// within its bound everywhere.
#[test]
fn quadratic_perspective_holds_where_affine_fails() {
    let texels = ramp_texels();
    let tex = [ramp(&texels)];
    let c = cfg(240, 240, (240, 240));
    let mut affine_fails = 0;
    for ratio in [1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 16.0, 32.0, 64.0] {
        let cmds = tilted_quad(240, 240, ratio);
        let [a, q, e] = TexKind::TEXTURED.map(|k| error(&c, &cmds, &tex, k));
        println!(
            "ratio {ratio}: affine {:.3} / {:.3}, quadratic {:.3} / {:.3}, exact {:.4} (max / mean texels, {} px)",
            a.max, a.mean, q.max, q.mean, e.max, a.pixels
        );
        assert!(
            e.max <= EXACT_LSB / 16.0,
            "exact mode at ratio {ratio}: {e:?}"
        );
        if ratio == 1.0 {
            // Constant q: every mode is the affine map.
            assert!(
                a.max <= EXACT_LSB / 16.0 && q.max <= EXACT_LSB / 16.0,
                "{a:?} {q:?}"
            );
        }
        if a.max > 2.0 {
            affine_fails += 1;
            assert!(q.max <= 0.5, "quadratic at ratio {ratio}: {q:?}");
        }
        assert!(q.mean < a.mean || ratio == 1.0, "ratio {ratio}");
    }
    assert!(
        affine_fails >= 3,
        "the workload must reach affine's failure"
    );
}

/// The quadratic mode's tolerance knob ([`TexKind::TOLERANCES`]): within
/// two texels the error stays below two texels at every depth ratio to
/// 64 (and its largest exceeds the half-texel default's); never split
/// (the seed's plain 32-pixel segments), it passes half a texel where the
/// depth changes fast, which is why the default splits.
#[test]
fn the_tolerance_knob_trades_texels_for_segments() {
    let texels = ramp_texels();
    let tex = [ramp(&texels)];
    let c = cfg(240, 240, (240, 240));
    let mut worst = [0.0f64; 3];
    for ratio in [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0] {
        let cmds = tilted_quad(240, 240, ratio);
        let [half, two, never] = TexKind::TOLERANCES.map(|k| error(&c, &cmds, &tex, k));
        println!(
            "ratio {ratio}: quadratic max {:.3} (0.5 texel), {:.3} (2 texels), {:.3} (never split)",
            half.max, two.max, never.max
        );
        assert!(half.max <= 0.5, "ratio {ratio}: {half:?}");
        assert!(two.max <= 2.0, "ratio {ratio}: {two:?}");
        for (w, e) in worst.iter_mut().zip([half, two, never]) {
            *w = w.max(e.max);
        }
    }
    assert!(
        worst[0] < worst[1] && worst[1] <= worst[2] && worst[2] > 0.5,
        "the looser, the larger the error: {worst:?}"
    );
}

/// Every mode (and tolerance) draws the same pixels whatever the tiling: spans are
/// interpolated over the whole covered row (at ratio 40 the quadratic
/// mode splits segments, and a tile entering a row mid-segment replays
/// the splits).
#[test]
fn tiling_does_not_change_the_output() {
    let texels = ramp_texels();
    let tex = [ramp(&texels)];
    let kinds = [TexKind::TEXTURED, TexKind::TOLERANCES].concat();
    for (ratio, kind) in [5.0, 40.0]
        .into_iter()
        .flat_map(|r| kinds.iter().map(move |&k| (r, k)))
    {
        let cmds = tilted_quad(96, 64, ratio);
        let whole = render_textured(&cfg(96, 64, (96, 64)), &cmds, &tex, kind, 0).unwrap();
        for tile in [(16, 16), (33, 7), (1, 64), (96, 1)] {
            let t = render_textured(&cfg(96, 64, tile), &cmds, &tex, kind, 0).unwrap();
            assert_eq!(t.raw, whole.raw, "{kind:?} ratio {ratio} tile {tile:?}");
        }
    }
}

/// Shade modulates the texel (`texel · shade / 255`, Gouraud-interpolated)
/// and a texture index past the frame's textures draws the shade alone.
#[test]
fn shade_modulates_and_missing_textures_draw_the_shade() {
    let texels = ramp_texels();
    let tex = [ramp(&texels)];
    let c = cfg(64, 48, (32, 16));
    let mut cmds = tilted_quad(64, 48, 2.0).to_vec();
    for cmd in &mut cmds {
        if let Command::Textured { shade, .. } = cmd {
            *shade = [255, 40, 128];
        }
    }
    let ours = render_textured(&c, &cmds, &tex, TexKind::Exact, 0).unwrap();
    let exact = reference::render_textured(&c, &cmds, &tex);
    let mut n = 0;
    for (i, p) in ours.raw.iter().enumerate() {
        if exact.depth[i] < 65535.0 {
            let r = ((p >> 16) & 255) as f64;
            // The texel is rounded to 8 bits, then multiplied by the shade
            // (interpolated linearly along the span: under 2^-8 LSB) and
            // rounded again.
            let e = (r - exact.color[i][0]).abs();
            assert!(
                e <= EXACT_LSB + 0.5 + 1.0 / 256.0,
                "pixel {i}: {r} vs {:?}",
                exact.color[i]
            );
            n += 1;
        }
    }
    assert!(n > 1000);
    for cmd in &mut cmds {
        if let Command::Textured { tex, .. } = cmd {
            *tex = 1;
        }
    }
    let ours = render_textured(&c, &cmds, &tex, TexKind::Quadratic, 0).unwrap();
    let exact = reference::render_textured(&c, &cmds, &tex);
    for (i, p) in ours.raw.iter().enumerate() {
        let (r, g) = ((p >> 16) & 255, (p >> 8) & 255);
        assert_eq!(r, g, "grey at {i}");
        assert!(
            (r as f64 - exact.color[i][0]).abs() <= 0.5 + 1.0 / 256.0,
            "{i}"
        );
    }
}

/// One random texture: format, size (powers of two and not), addressing,
/// filter.
fn arb_texture() -> impl Strategy<Value = (TexFormat, u16, u16, Vec<u8>, Vec<Rgb>, Wrap, Filter)> {
    (
        prop_oneof![
            Just(TexFormat::Rgb565),
            Just(TexFormat::Rgb888),
            Just(TexFormat::Gray8),
            Just(TexFormat::Indexed8)
        ],
        1u16..10,
        1u16..10,
        prop_oneof![Just(Wrap::Repeat), Just(Wrap::Clamp)],
        prop_oneof![Just(Filter::Nearest), Just(Filter::Bilinear)],
        any::<u64>(),
    )
        .prop_map(|(f, w, h, wrap, filter, seed)| {
            let mut rng = tilerast_tests::Rng::new(seed);
            let data = (0..w as usize * h as usize * f.bytes())
                .map(|_| rng.byte())
                .collect();
            let pal = (0..1 + rng.range(0, 200)).map(|_| rng.rgb()).collect();
            (f, w, h, data, pal, wrap, filter)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(tilerast_tests::cases(400)))]

    /// `Texture::sample` against the f64 sampler at random points (inside,
    /// outside, on texel edges): nearest reads the same texel, bilinear is
    /// within half an LSB plus the fractions' truncation.
    #[test]
    fn texel_reads_match_the_f64_sampler(
        (f, w, h, data, pal, wrap, filter) in arb_texture(),
        uv in proptest::collection::vec((-40_000i64..40_000, -40_000i64..40_000), 16),
    ) {
        let t = if f == TexFormat::Indexed8 {
            Texture::indexed(&data, &pal, w, h)
        } else {
            Texture::new(&data, w, h, f)
        }.unwrap().wrap(wrap).filter(filter);
        for (u, v) in uv {
            // 1/1024 texel steps, exact in f64 and in 32.32.
            let (u, v) = (u << 22, v << 22);
            let ours = t.sample(u, v);
            let exact = reference::sample(&t, u as f64 / 2f64.powi(32), v as f64 / 2f64.powi(32));
            let got = [ours.r, ours.g, ours.b];
            for k in 0..3 {
                let bound = match filter {
                    Filter::Nearest => 0.0,
                    Filter::Bilinear => 0.5 + 2.0 * 255.0 / 256.0,
                };
                prop_assert!((got[k] as f64 - exact[k]).abs() <= bound, "channel {} at ({}, {}): {:?} vs {:?}", k, u, v, ours, exact);
            }
        }
    }

    /// Random textured triangles (sub-pixel, partly off screen, random
    /// `q` down to 1/64 of the largest — the documented domain: `q`
    /// scaled so the largest is near 65535): the exact mode within its bound of the f64 mapping on the
    /// ramp; with equal `q`s every mode is.
    #[test]
    fn exact_mode_matches_the_f64_mapping(
        p in proptest::array::uniform3((-160i32..1200, -160i32..900)),
        uv in proptest::array::uniform3((0u16..256, 0u16..256)),
        q in proptest::array::uniform3(1024u16..=u16::MAX),
        flat in any::<bool>(),
        tile in (1u16..5, 1u16..5),
    ) {
        let texels = ramp_texels();
        let tex = [ramp(&texels)];
        let q = if flat { [q[0]; 3] } else { q };
        let v = core::array::from_fn(|k| TexVertex {
            x: Coord::from_bits(p[k].0),
            y: Coord::from_bits(p[k].1),
            z: 100,
            u: uv[k].0,
            v: uv[k].1,
            q: q[k],
        });
        let cmds = [Command::textured(0, v, [255; 3])];
        let c = cfg(64, 48, (tile.0 * 16, tile.1 * 16));
        let kinds: &[TexKind] = if flat { &TexKind::TEXTURED } else { &[TexKind::Exact] };
        for &kind in kinds {
            let e = error(&c, &cmds, &tex, kind);
            prop_assert!(e.max <= EXACT_LSB / 16.0, "{:?}: {:?}", kind, e);
        }
    }
}

/// OBJ `vt` and `.mtl` `map_Kd`: the crate's 24 face corners each keep
/// their texture coordinates, and its material names its PNG beside it.
#[test]
fn obj_texture_coordinates_and_map_kd_are_read() {
    let repo = tilerast_tests::repo();
    let obj = tilerast_sim::obj::load(
        &repo.join("assets/models/crate.obj"),
        &tilerast_sim::Limits::default(),
    )
    .unwrap();
    let m = &obj.models[0];
    assert_eq!((obj.models.len(), m.triangles.len()), (1, 12));
    assert_eq!((m.positions.len(), m.texcoords.len()), (24, 24));
    // Every face is the unit square of the texture.
    for t in &m.texcoords {
        assert!(t.iter().all(|&c| c == 0.0 || c == 1.0), "{t:?}");
    }
    let map = obj.materials[m.material.unwrap()]
        .diffuse_map
        .clone()
        .unwrap();
    assert_eq!(map, repo.join("assets/models/crate.png"));
}

/// A scene of one textured mesh, 96x96 RGB888 without dither.
fn mesh_scene(mesh: &str) -> tilerast_sim::Scene {
    let src = format!(
        "[screen]\nwidth = 96\nheight = 96\nformat = \"rgb888\"\ntile = [32, 32]\n\
         background = [0, 0, 0]\n\n[[command]]\nkind = \"mesh\"\n{mesh}\ncull_back = true\n"
    );
    tilerast_sim::Scene::parse(&src, &tilerast_tests::repo().join("scenes")).unwrap()
}

/// Largest and mean channel difference over the pixels the reference
/// covers, and how many distinct colours they hold.
fn against_reference(s: &tilerast_sim::Scene) -> (u8, f64, usize) {
    let ours = s.render().unwrap().image;
    let exact = s.reference();
    let img = exact.to_image();
    let (mut max, mut sum, mut n) = (0u8, 0.0, 0usize);
    let mut colours = std::collections::HashSet::new();
    for (i, d) in exact.depth.iter().enumerate() {
        if *d >= 65535.0 {
            continue;
        }
        let (a, b) = (ours.pixels[i], img.pixels[i]);
        for k in 0..3 {
            let e = a[k].abs_diff(b[k]);
            max = max.max(e);
            sum += e as f64;
        }
        n += 3;
        colours.insert(a);
    }
    (max, sum / n.max(1) as f64, colours.len())
}

/// The crate, textured through its `vt` and `map_Kd`, in each perspective
/// mode against the f64 reference of the same commands (exact
/// perspective, f64 bilinear, f64 Gouraud shade): the exact mode within 2
/// LSB everywhere (the texel bound above, 0.6 LSB, plus the shade's
/// rounding, under 1 LSB, times a texel), the quadratic within 4 (measured
/// 1 and 3; means 0.12 and 0.16); and the texture shows.
#[test]
fn textured_obj_mesh_matches_the_reference() {
    let mut s = mesh_scene(
        "obj = \"../assets/models/crate.obj\"\neye = [2.2, 1.8, 2.6]\nfov = 45\nrotate_y = 15",
    );
    assert_eq!((s.textures.len(), s.mesh.untextured), (1, 0));
    let textured = s
        .commands
        .iter()
        .filter(|c| matches!(c, Command::Textured { .. }))
        .count();
    assert_eq!(textured, 6, "three faces face the camera");
    for (kind, max_lsb, mean_lsb) in [(TexKind::Exact, 2, 0.2), (TexKind::Quadratic, 4, 0.25)] {
        s.texturing = kind;
        let (max, mean, colours) = against_reference(&s);
        println!(
            "{}: max {max}, mean {mean:.3} LSB, {colours} colours",
            kind.name()
        );
        assert!(
            max <= max_lsb && mean <= mean_lsb,
            "{}: {max} {mean}",
            kind.name()
        );
        assert!(colours > 50, "the texture shows: {colours} colours");
    }
    // Untextured, the same faces draw their white-lit shade: grey.
    s.texturing = TexKind::None;
    let img = s.render().unwrap().image;
    assert!(img.pixels.iter().all(|p| p[0] == p[1] && p[1] == p[2]));
}

/// The teapot has no `vt`: a spherical projection textures every
/// triangle the geometry stage draws whole, and the seam is unwrapped
/// per triangle (no triangle spans more than half the texture in `u`
/// besides its repeats); quadratic perspective within 3 LSB of the f64
/// reference (measured 2, mean 0.11).
#[test]
fn projected_coordinates_texture_a_model_without_vt() {
    let s = mesh_scene(
        "obj = \"../assets/models/teapot.obj\"\ntexture = \"../assets/textures/checker.png\"\n\
         uv = \"spherical\"\nuv_scale = [2, 1]",
    );
    let mut n = 0;
    for c in &s.commands {
        let Command::Textured { v, .. } = c else {
            panic!("every face is textured: {c:?}");
        };
        let us = v.map(|t| t.u as f64 / 16.0);
        let span = us.iter().cloned().fold(f64::MIN, f64::max)
            - us.iter().cloned().fold(f64::MAX, f64::min);
        assert!(span <= 64.0 * 2.0 / 2.0, "u spans {span} texels: {us:?}");
        n += 1;
    }
    assert!(n > 2000, "{n} textured triangles");
    let (max, mean, _) = against_reference(&s);
    println!("teapot: max {max}, mean {mean:.3} LSB");
    assert!(max <= 3 && mean <= 0.2, "{max} {mean}");
}
