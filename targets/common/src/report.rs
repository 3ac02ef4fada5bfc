//! The report a firmware prints, one `key value ...` line per measurement,
//! parsed by the host (`tests/tests/firmware.rs`). The same functions run on
//! the host with any clock, so the host computes the CRCs the boards must
//! print.

use crate::workloads::{
    self, AREA_AA_CMDS, EDGE_AA_CMDS, FILL_CMDS, LARGE_BLEND_CMDS, LARGE_QUAD_CMDS, LARGE_TEX_CMDS,
    LARGE_TRIANGLE_CMDS, LINE_CMDS, TRIANGLE_CMDS, WU_LINE_CMDS,
};
use crate::{run_scene, Clock, SceneRun};
use core::fmt::Write;
use embedded_graphics::{pixelcolor::IntoStorage, prelude::Size};
use tilerast::hash::CrcTarget;
use tilerast::prelude::*;

/// A scene the firmware knows: its tile types and its label.
pub trait SceneKind {
    /// The tile's planes.
    type C: TileConfig;
    /// Name in the report (and of the exported `.bin`).
    const NAME: &'static str;
    /// Text drawn over every tile with `embedded-graphics`.
    const LABEL: Option<&'static str>;
}

/// `scenes/demo.toml`: RGB444, Z, window IDs, 8x8 dither, labelled; its
/// mesh (the teapot) under the plane contract ([`PlaneContract`]: the
/// encoded mesh's triangles go to the tile's fused mesh path; the other
/// commands are exact either way). The dither hides the contracts'
/// one-unit differences: the frame's CRC is the exact contract's.
pub struct Demo;
impl SceneKind for Demo {
    type C = Planes<Rgb444Format, Depth16, Wid8, Bayer8, NoAa, PlaneContract>;
    const NAME: &'static str = "demo";
    const LABEL: Option<&'static str> = Some("tilerast");
}

/// `scenes/teapot.toml`: the teapot alone, RGB565 + 16-bit Z, Gouraud, no
/// dither: the frame the issue tracker compares with the C++ MCU libraries.
pub struct Teapot;
impl SceneKind for Teapot {
    type C = Planes<Rgb565Format, Depth16, NoWid, NoDither>;
    const NAME: &'static str = "teapot";
    const LABEL: Option<&'static str> = None;
}

/// `scenes/teapot_cull.toml`: the [`Teapot`] frame with back-face culling
/// in the raster stage (`State::cull`): the binning drops the triangles
/// facing away.
pub struct TeapotCull;
impl SceneKind for TeapotCull {
    type C = Planes<Rgb565Format, Depth16, NoWid, NoDither>;
    const NAME: &'static str = "teapot_cull";
    const LABEL: Option<&'static str> = None;
}

/// `scenes/ssd1306.toml`: 1 bit per pixel, Z, 4x4 dither; a mesh, so its
/// tile draws triangles and fills only ([`Triangles`]: no line, span, edge
/// or fast-Phong code in its firmware).
pub struct Ssd1306;
impl SceneKind for Ssd1306 {
    type C = MeshPlanes<BinaryFormat, Depth16, NoWid, Bayer4>;
    const NAME: &'static str = "ssd1306";
    const LABEL: Option<&'static str> = None;
}

/// Renders scene `K` in tiles of `tile` (at most `8 N` pixels) into a
/// [`CrcTarget`]: the CRC of the pixel stream and the run's costs.
pub fn scene_crc<K: SceneKind, const N: usize, const BC: usize, const BT: usize>(
    scene: &[u8],
    tile: (u16, u16),
    clock: &mut impl Clock,
) -> Result<(u32, SceneRun), Error>
where
    <<K::C as TileConfig>::Format as PixelFormat>::Color: IntoStorage,
    <<<K::C as TileConfig>::Format as PixelFormat>::Color as IntoStorage>::Storage: Into<u32>,
{
    let (h, _) = tilerast::wire::SceneHeader::parse(scene)?;
    let mut target = CrcTarget::<<<K::C as TileConfig>::Format as PixelFormat>::Color>::new(
        Size::new(h.width as u32, h.height as u32),
    );
    let mut buf: Tile<N, K::C> = Tile::new();
    let mut bins: Bins<BC, BT> = Bins::new();
    let run = run_scene(
        scene,
        &mut buf,
        &mut bins,
        tile,
        K::LABEL,
        &mut target,
        clock,
    )?;
    Ok((target.crc(), run))
}

/// Prints `scene NAME tile WxH crc 0x... pixels P raster_ticks R flush_ticks F
/// replayed C bin_passes B bin_peak E unbinned U`, rendered with bins of
/// `BC` entries for `BT` tiles.
#[inline(never)] // its tile and bins leave the stack before the next scene's
pub fn report_scene<K: SceneKind, const N: usize, const BC: usize, const BT: usize>(
    scene: &[u8],
    tile: (u16, u16),
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result
where
    <<K::C as TileConfig>::Format as PixelFormat>::Color: IntoStorage,
    <<<K::C as TileConfig>::Format as PixelFormat>::Color as IntoStorage>::Storage: Into<u32>,
{
    match scene_crc::<K, N, BC, BT>(scene, tile, clock) {
        Ok((crc, r)) => writeln!(
            out,
            "scene {} tile {}x{} crc 0x{crc:08x} pixels {} raster_ticks {} flush_ticks {} \
             replayed {} bin_passes {} bin_peak {} unbinned {}",
            K::NAME,
            tile.0,
            tile.1,
            r.pixels,
            r.raster_ticks,
            r.flush_ticks,
            r.stats.replayed,
            r.stats.bin_passes,
            r.stats.bin_peak,
            r.stats.unbinned_tiles
        ),
        Err(e) => writeln!(out, "scene {} error {e}", K::NAME),
    }
}

/// Prints `trade ssd1306 tile WxH bins B bytes M crc 0x... raster_ticks R
/// flush_ticks F bin_passes P`: the SSD1306 scene in tiles of `tile` (at
/// most `8 N` pixels) with bins of `BC` entries, and `M` the bytes its tile
/// and bins take — one point of the RAM-against-instructions trade.
#[inline(never)] // its tile and bins leave the stack before the next point's
pub fn report_ssd_trade<const N: usize, const BC: usize, const BT: usize>(
    scene: &[u8],
    tile: (u16, u16),
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    let bytes = core::mem::size_of::<Tile<N, <Ssd1306 as SceneKind>::C>>()
        + core::mem::size_of::<Bins<BC, BT>>();
    match scene_crc::<Ssd1306, N, BC, BT>(scene, tile, clock) {
        Ok((crc, r)) => writeln!(
            out,
            "trade ssd1306 tile {}x{} bins {BC} bytes {bytes} crc 0x{crc:08x} raster_ticks {} \
             flush_ticks {} bin_passes {}",
            tile.0, tile.1, r.raster_ticks, r.flush_ticks, r.stats.bin_passes
        ),
        Err(e) => writeln!(out, "trade ssd1306 error {e}"),
    }
}

/// Prints `phases NAME bin B clear C decode D setup S traverse T all A`:
/// ticks to render the scene until each phase (cumulative).
#[inline(never)]
pub fn report_phases<K: SceneKind, const N: usize, const BC: usize, const BT: usize>(
    scene: &[u8],
    tile: (u16, u16),
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    let mut buf: Tile<N, K::C> = Tile::new();
    let mut bins: Bins<BC, BT> = Bins::new();
    match crate::phase_ticks(scene, &mut buf, &mut bins, tile, clock) {
        Ok([b, c, d, s, t, a]) => writeln!(
            out,
            "phases {} bin {b} clear {c} decode {d} setup {s} traverse {t} all {a}",
            K::NAME
        ),
        Err(e) => writeln!(out, "phases {} error {e}", K::NAME),
    }
}

/// Prints `volume MODE prepare P setup S phase1 A phase2 B samples N
/// composited C skipped K crc X` for each of [`crate::volumes::MODES`]
/// ([`crate::volumes`]; 133 KB of volume on the stack).
#[inline(never)]
pub fn report_volume(out: &mut impl Write, clock: &mut impl Clock) -> core::fmt::Result {
    use crate::volumes::{BRICK_BYTES, CELL_BYTES, MODES, VOXELS};
    let mut density = [0u8; VOXELS];
    let mut normals = [0u8; 3 * VOXELS];
    let mut bricks = [0u8; BRICK_BYTES];
    let mut cells = [0u8; CELL_BYTES];
    match crate::volumes::run(&mut density, &mut normals, &mut bricks, &mut cells, clock) {
        Ok(runs) => {
            for (mode, r) in MODES.iter().zip(runs) {
                let s = r.stats;
                writeln!(
                    out,
                    "volume {mode} prepare {} setup {} phase1 {} phase2 {} samples {} composited {} skipped {} crc 0x{:08x}",
                    r.prepare, r.setup, r.phase1, r.phase2, s.samples, s.composited, s.skipped, r.crc
                )?;
            }
            Ok(())
        }
        Err(e) => writeln!(out, "volume error {e}"),
    }
}

/// Prints `cull MODE ticks T vertices V tested B culled C drawn O
/// commands K prims_culled P reads R crc X` for each culling mode over
/// the city walk ([`crate::city`]; 32 KB of vertex cache on the stack).
#[inline(never)]
pub fn report_city(out: &mut impl Write, clock: &mut impl Clock) -> core::fmt::Result {
    let mut slots = [tilerast::geometry::VertexSlot::EMPTY; crate::city::FW_SLOTS];
    for mode in tilerast::occlusion::CullMode::ALL {
        match crate::city::run_fw(mode, &mut slots, clock) {
            Ok(r) => writeln!(
                out,
                "cull {} ticks {} vertices {} tested {} culled {} drawn {} commands {} prims_culled {} reads {} crc 0x{:08x}",
                mode.name(),
                r.ticks,
                r.vertices,
                r.stats.boxes_tested,
                r.stats.nodes_culled,
                r.stats.objects_drawn,
                r.stats.commands,
                r.stats.prims_culled,
                r.stats.cost.reads,
                r.crc
            )?,
            Err(e) => writeln!(out, "cull {} error {e}", mode.name())?,
        }
    }
    Ok(())
}

/// Prints `anim MODE frames F tiles T drawn D sent_tiles S bytes_full B
/// bytes_sent P ticks K` for each way of finding changed tiles: the
/// animated gauge with partial updates ([`crate::anim`]).
#[inline(never)]
pub fn report_anim(out: &mut impl Write, clock: &mut impl Clock) -> core::fmt::Result {
    use crate::anim::Changes;
    let mut tile = crate::anim::AnimTile::new();
    for (name, changes) in [("output", Changes::Output), ("input", Changes::Input)] {
        match crate::anim::run(&mut tile, clock, changes, |_| {}) {
            Ok(r) => writeln!(
                out,
                "anim {name} frames {} tiles {} drawn {} sent_tiles {} bytes_full {} bytes_sent {} ticks {}",
                crate::anim::FRAMES,
                r.tiles,
                r.drawn,
                r.sent_tiles,
                r.bytes_full,
                r.bytes_sent,
                r.ticks
            )?,
            Err(e) => writeln!(out, "anim {name} error {e}")?,
        }
    }
    Ok(())
}

/// How a workload is drawn.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Via {
    /// The tilerast command itself.
    Ours,
    /// The tilerast command with the workloads' textures.
    Textured,
    /// `embedded-graphics`' own primitive for it.
    EmbeddedGraphics,
}

#[inline(never)]
fn bench_one<C: TileConfig>(
    name: &str,
    cmds: &[Command],
    via: Via,
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    let mut tile: Tile<{ (workloads::SIDE * workloads::SIDE / 8) as usize }, C> = Tile::new();
    let ticks = match via {
        Via::Ours => workloads::draw(&mut tile, cmds, &[], clock),
        Via::Textured => workloads::draw(&mut tile, cmds, &workloads::TEXTURES, clock),
        Via::EmbeddedGraphics => workloads::eg_primitives(&mut tile, cmds, clock),
    };
    match ticks {
        Ok(t) => writeln!(
            out,
            "bench {name} ticks {t} crc 0x{:08x}",
            workloads::tile_crc(&tile)
        ),
        Err(e) => writeln!(out, "bench {name} error {e}"),
    }
}

/// Prints the workloads that do not fit beside the others on the
/// micro:bit (feature `bench_extra`, a build of its own there: each tile
/// configuration is a copy of the draw code): area sampling (seed 001
/// §IV.5: the small triangles with every edge flagged,
/// [`workloads::AreaAaBench`]); the textured walls in perspective, affine,
/// quadratic and exact (moved here when the Gouraud draw's second copy of
/// its row loop filled the other build's flash); and the quadratic
/// texture mode's tolerance knob, within two texels and never split (the
/// seed's plain 32-pixel segments).
pub fn report_extra_benches(out: &mut impl Write, clock: &mut impl Clock) -> core::fmt::Result {
    bench_one::<workloads::AreaAaBench>(
        "gouraud_z_area_aa_rgb565",
        &AREA_AA_CMDS,
        Via::Ours,
        out,
        clock,
    )?;
    let tex: &[Command] = &LARGE_TEX_CMDS;
    bench_one::<workloads::TexBench<AffineTexturing>>(
        "large_tex_affine_z_rgb565",
        tex,
        Via::Textured,
        out,
        clock,
    )?;
    bench_one::<workloads::TexBench<QuadraticTexturing>>(
        "large_tex_quadratic_z_rgb565",
        tex,
        Via::Textured,
        out,
        clock,
    )?;
    bench_one::<workloads::TexBench<ExactTexturing>>(
        "large_tex_exact_z_rgb565",
        tex,
        Via::Textured,
        out,
        clock,
    )?;
    bench_one::<workloads::TexBench<QuadraticTexturing<16>>>(
        "large_tex_quadratic_2texel_z_rgb565",
        tex,
        Via::Textured,
        out,
        clock,
    )?;
    bench_one::<workloads::TexBench<QuadraticTexturing<{ tilerast::texture::NEVER_SPLIT }>>>(
        "large_tex_quadratic_nosplit_z_rgb565",
        tex,
        Via::Textured,
        out,
        clock,
    )
}

/// Prints `bench NAME ticks T` for each workload: flat fill; Gouraud
/// alone, with Z, with Z and window ID, and with those and 8x8 dither (all
/// RGB565), and with Z and with Z, window ID and dither under the plane
/// contract; large Gouraud triangles alone, with Z, and with Z, window ID
/// and dither; the same translucent (alpha-blended, with Z) and fast
/// Phong; and with Z and every edge antialiased (seed 003's edges, and area sampling through
/// the α-channel); the same triangles through `embedded-graphics`' `Triangle`
/// fill; lines, Bresenham and two-point (Wu) antialiased, and the same
/// lines through `embedded-graphics`' `Line`.
pub fn report_benches(out: &mut impl Write, clock: &mut impl Clock) -> core::fmt::Result {
    let tris: &[Command] = &TRIANGLE_CMDS;
    bench_one::<Rgb565Format>("fill_rgb565", &FILL_CMDS, Via::Ours, out, clock)?;
    bench_one::<Rgb565Format>("gouraud_rgb565", tris, Via::Ours, out, clock)?;
    bench_one::<Planes<Rgb565Format, Depth16, NoWid, NoDither>>(
        "gouraud_z_rgb565",
        tris,
        Via::Ours,
        out,
        clock,
    )?;
    bench_one::<Planes<Rgb565Format, Depth16, NoWid, NoDither>>(
        "gouraud_z_edge_aa_rgb565",
        &EDGE_AA_CMDS,
        Via::Ours,
        out,
        clock,
    )?;
    bench_one::<Planes<Rgb565Format, Depth16, Wid8, NoDither>>(
        "gouraud_z_wid_rgb565",
        tris,
        Via::Ours,
        out,
        clock,
    )?;
    bench_one::<Planes<Rgb565Format, Depth16, Wid8, Bayer8>>(
        "gouraud_z_wid_dither8_rgb565",
        tris,
        Via::Ours,
        out,
        clock,
    )?;
    // Not in the micro:bit's workload build: two more copies of the
    // triangle path overflow its 256 KB of flash (by 30 KB, measured).
    #[cfg(target_has_atomic = "32")]
    {
        bench_one::<workloads::PlaneZBench>("gouraud_z_plane_rgb565", tris, Via::Ours, out, clock)?;
        bench_one::<workloads::PlaneZWidDitherBench>(
            "gouraud_z_wid_dither8_plane_rgb565",
            tris,
            Via::Ours,
            out,
            clock,
        )?;
    }
    let large: &[Command] = &LARGE_TRIANGLE_CMDS;
    bench_one::<Rgb565Format>("large_gouraud_rgb565", large, Via::Ours, out, clock)?;
    bench_one::<Planes<Rgb565Format, Depth16, NoWid, NoDither>>(
        "large_gouraud_z_rgb565",
        large,
        Via::Ours,
        out,
        clock,
    )?;
    bench_one::<Planes<Rgb565Format, Depth16, Wid8, Bayer8>>(
        "large_gouraud_z_wid_dither8_rgb565",
        large,
        Via::Ours,
        out,
        clock,
    )?;
    bench_one::<workloads::BlendBench>(
        "large_blend_z_rgb565",
        &LARGE_BLEND_CMDS,
        Via::Ours,
        out,
        clock,
    )?;
    bench_one::<workloads::QuadBench>(
        "large_phong_z_rgb565",
        &LARGE_QUAD_CMDS,
        Via::Ours,
        out,
        clock,
    )?;
    let mut buf = [0u16; (workloads::SIDE * workloads::SIDE) as usize];
    let (t, crc) = workloads::exact_phong::<f32>(&mut buf, clock);
    writeln!(
        out,
        "bench exact_phong_f32_rgb565 ticks {t} crc 0x{crc:08x}"
    )?;
    let (t, crc) = workloads::exact_phong::<tilerast::geometry::Fx>(&mut buf, clock);
    writeln!(
        out,
        "bench exact_phong_fixed_rgb565 ticks {t} crc 0x{crc:08x}"
    )?;
    bench_one::<Rgb565Format>(
        "eg_triangle_rgb565",
        tris,
        Via::EmbeddedGraphics,
        out,
        clock,
    )?;
    bench_one::<Rgb565Format>("bresenham_rgb565", &LINE_CMDS, Via::Ours, out, clock)?;
    bench_one::<Rgb565Format>("wu_rgb565", &WU_LINE_CMDS, Via::Ours, out, clock)?;
    bench_one::<Rgb565Format>(
        "eg_line_rgb565",
        &LINE_CMDS,
        Via::EmbeddedGraphics,
        out,
        clock,
    )
}

/// Prints one line per frame of a rotating mesh drawn by the geometry stage
/// in back end `S`: `spin NAME backend B frame K crc 0x... vertex_ticks V
/// raster_ticks R flush_ticks F vertices N lit L front F clipped C culled U replayed P`.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub fn report_spin<
    S: tilerast::geometry::Real,
    const N: usize,
    const BC: usize,
    const BT: usize,
>(
    name: &str,
    mesh: &tilerast::geometry::Mesh<'_>,
    slots: &mut [tilerast::geometry::VertexSlot],
    tile: (u16, u16),
    frames: u32,
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    let mut res = Ok(());
    let backend = if S::NAME == "f32" { "f32" } else { "fixed" };
    let r = crate::spin::run::<S, N, BC, BT>(mesh, slots, tile, frames, clock, |k, f| {
        let g = &f.geometry;
        res = res.and_then(|()| {
            writeln!(
                out,
                "spin {name} backend {backend} frame {k} frames {frames} crc 0x{:08x} vertex_ticks {} raster_ticks {} \
                 flush_ticks {} vertices {} lit {} front {} clipped {} culled {} replayed {}",
                f.crc,
                f.vertex_ticks,
                f.raster_ticks,
                f.flush_ticks,
                g.vertices,
                g.lit,
                g.front,
                g.clipped,
                g.culled,
                f.frame.replayed
            )
        });
    });
    res?;
    match r {
        Ok(()) => Ok(()),
        Err(e) => writeln!(out, "spin {name} backend {backend} error {e}"),
    }
}

/// Prints `geom NAME backend B frame K frames F vertex_ticks V vertices N
/// lit L hash 0x...` for `frames` frames of the vertex stage alone
/// ([`crate::spin::vertex_stage`]): the per-vertex cost of a back end, and
/// its output checked against the host without rasterizing.
#[inline(never)]
pub fn report_geom<S: tilerast::geometry::Real>(
    name: &str,
    mesh: &tilerast::geometry::Mesh<'_>,
    slots: &mut [tilerast::geometry::VertexSlot],
    frames: u32,
    out: &mut impl Write,
    clock: &mut impl Clock,
) -> core::fmt::Result {
    let backend = if S::NAME == "f32" { "f32" } else { "fixed" };
    for k in 0..frames {
        match crate::spin::vertex_stage::<S>(mesh, slots, (k, frames), clock) {
            Ok((g, ticks, hash)) => writeln!(
                out,
                "geom {name} backend {backend} frame {k} frames {frames} vertex_ticks {ticks} \
                 vertices {} lit {} hash 0x{hash:08x}",
                g.vertices, g.lit
            )?,
            Err(e) => return writeln!(out, "geom {name} backend {backend} error {e}"),
        }
    }
    Ok(())
}
