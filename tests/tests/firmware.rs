//! Bit-identical output on x86-64 and four microcontroller instruction sets
//! (ARMv6-M, ARMv7E-M, ARMv8-M Mainline, RV32IMAC): builds each QEMU
//! firmware under `targets/`, runs it under QEMU with `-icount shift=0`,
//! and asserts that the CRC32 of every scene's pixel stream equals the one
//! the host computes with the same code, and that each board's clock
//! counts a loop of known length right. With `TILERAST_REPORT=path` it also
//! writes the cost report (instructions per pixel, flash, RAM, stack).
//!
//! Needs `qemu-system-arm`, `qemu-system-riscv32` and the Rust targets, so
//! it is `#[ignore]`d in a plain `cargo test`; `cargo xtask test` installs
//! them and runs it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tilerast::prelude::{AffineTexturing, ExactTexturing, QuadraticTexturing};
use tilerast::texture::NEVER_SPLIT;
use tilerast_fw::report::{scene_crc, Demo, Ssd1306, Teapot, TeapotCull};
use tilerast_fw::workloads::{self, FILL_CMDS, LARGE_TRIANGLE_CMDS, LINE_CMDS, TRIANGLE_CMDS};

mod qemu;
use qemu::{build_for, build_small, build_with, export_scenes, run_with};

/// Builds a board's firmware with `features` (its default ones for `None`).
fn build(board: &str, scenes: &Path, features: Option<&str>) -> PathBuf {
    build_with(board, scenes, features, false)
}

/// Runs a firmware ELF under QEMU; returns what it printed.
fn run(board: &str, elf: &Path) -> String {
    run_with(board, elf, &[])
}

/// One `scene` line of a firmware report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct SceneLine {
    tile: (u16, u16),
    crc: u32,
    pixels: u64,
    raster_ticks: u64,
    flush_ticks: u64,
}

/// One board's report, parsed.
#[derive(Debug, Default)]
struct Report {
    board: String,
    instr_per_tick: f64,
    /// The clock's calibration: (loop instructions, ticks it took).
    calibration: (u64, u64),
    scenes: BTreeMap<String, SceneLine>,
    benches: BTreeMap<String, u64>,
    /// The CRC32 of the tile each workload leaves.
    bench_crcs: BTreeMap<String, u32>,
    /// Per scene: ticks until each phase (bin, clear, decode, setup, traverse, all).
    phases: BTreeMap<String, [u64; 6]>,
    /// The animated gauge, per way of finding changes (`output`, `input`):
    /// (frames, tiles, drawn, sent tiles, bytes full, bytes sent, ticks).
    anim: BTreeMap<String, [u64; 7]>,
    /// Per scene: (bin passes, bin peak, unbinned tiles, replayed).
    bins: BTreeMap<String, [u64; 4]>,
    /// Rotating meshes drawn by the on-device geometry stage, one per frame.
    spins: Vec<SpinLine>,
    /// The vertex stage alone, one per frame.
    geoms: Vec<GeomLine>,
    /// The volume workload per mode: (prepare, setup, phase I, phase II,
    /// samples, composited, crc).
    volumes: BTreeMap<String, [u64; 8]>,
    /// The culled city per mode: (ticks, vertices, tested, culled, drawn,
    /// commands, prims culled, reads, crc).
    culls: BTreeMap<String, [u64; 9]>,
    /// The SSD1306 scene's RAM-against-instructions points.
    trades: Vec<TradeLine>,
    stack_used: u64,
}

/// One `trade` line: the SSD1306 scene in one tile size and bin capacity.
#[derive(Debug, Clone, PartialEq, Eq)]
struct TradeLine {
    tile: (u16, u16),
    bins: u64,
    bytes: u64,
    crc: u32,
    raster_ticks: u64,
    flush_ticks: u64,
    passes: u64,
}

/// One `geom` line: the vertex stage alone for a frame.
#[derive(Debug, Clone, PartialEq, Eq)]
struct GeomLine {
    mesh: String,
    backend: String,
    frame: u32,
    frames: u32,
    vertex_ticks: u64,
    vertices: u64,
    hash: u32,
}

/// One `spin` line: a frame of a rotating mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
struct SpinLine {
    mesh: String,
    backend: String,
    frame: u32,
    frames: u32,
    crc: u32,
    vertex_ticks: u64,
    raster_ticks: u64,
    flush_ticks: u64,
    vertices: u64,
    lit: u64,
    front: u64,
    clipped: u64,
}

fn field<'a>(words: &'a [&'a str], key: &str) -> &'a str {
    let i = words
        .iter()
        .position(|w| *w == key)
        .unwrap_or_else(|| panic!("no `{key}` in {words:?}"));
    words[i + 1]
}

fn parse(out: &str) -> Report {
    let mut r = Report::default();
    assert!(
        out.lines().any(|l| l == "done"),
        "firmware did not finish:\n{out}"
    );
    for line in out.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first().copied() {
            Some("board") => {
                r.board = w[1].to_string();
                r.instr_per_tick = field(&w, "instr_per_tick").parse().unwrap();
            }
            Some("scene") => {
                assert!(!w.contains(&"error"), "{line}");
                let (tw, th) = field(&w, "tile").split_once('x').unwrap();
                let crc =
                    u32::from_str_radix(field(&w, "crc").trim_start_matches("0x"), 16).unwrap();
                let num = |k: &str| field(&w, k).parse::<u64>().unwrap();
                let line = SceneLine {
                    tile: (tw.parse().unwrap(), th.parse().unwrap()),
                    crc,
                    pixels: num("pixels"),
                    raster_ticks: num("raster_ticks"),
                    flush_ticks: num("flush_ticks"),
                };
                r.bins.insert(
                    w[1].to_string(),
                    [
                        num("bin_passes"),
                        num("bin_peak"),
                        num("unbinned"),
                        num("replayed"),
                    ],
                );
                r.scenes.insert(w[1].to_string(), line);
            }
            Some("bench") => {
                assert!(!w.contains(&"error"), "{line}");
                r.benches
                    .insert(w[1].to_string(), field(&w, "ticks").parse().unwrap());
                let crc = field(&w, "crc").trim_start_matches("0x");
                r.bench_crcs
                    .insert(w[1].to_string(), u32::from_str_radix(crc, 16).unwrap());
            }
            Some("phases") => {
                assert!(!w.contains(&"error"), "{line}");
                let k = ["bin", "clear", "decode", "setup", "traverse", "all"]
                    .map(|k| field(&w, k).parse::<u64>().unwrap());
                r.phases.insert(w[1].to_string(), k);
            }
            Some("anim") => {
                assert!(!w.contains(&"error"), "{line}");
                r.anim.insert(
                    w[1].to_string(),
                    [
                        "frames",
                        "tiles",
                        "drawn",
                        "sent_tiles",
                        "bytes_full",
                        "bytes_sent",
                        "ticks",
                    ]
                    .map(|k| field(&w, k).parse::<u64>().unwrap()),
                );
            }
            Some("spin") => {
                assert!(!w.contains(&"error"), "{line}");
                let num = |k: &str| field(&w, k).parse::<u64>().unwrap();
                r.spins.push(SpinLine {
                    mesh: w[1].to_string(),
                    backend: field(&w, "backend").to_string(),
                    frame: num("frame") as u32,
                    frames: num("frames") as u32,
                    crc: u32::from_str_radix(field(&w, "crc").trim_start_matches("0x"), 16)
                        .unwrap(),
                    vertex_ticks: num("vertex_ticks"),
                    raster_ticks: num("raster_ticks"),
                    flush_ticks: num("flush_ticks"),
                    vertices: num("vertices"),
                    lit: num("lit"),
                    front: num("front"),
                    clipped: num("clipped"),
                });
            }
            Some("geom") => {
                assert!(!w.contains(&"error"), "{line}");
                let num = |k: &str| field(&w, k).parse::<u64>().unwrap();
                r.geoms.push(GeomLine {
                    mesh: w[1].to_string(),
                    backend: field(&w, "backend").to_string(),
                    frame: num("frame") as u32,
                    frames: num("frames") as u32,
                    vertex_ticks: num("vertex_ticks"),
                    vertices: num("vertices"),
                    hash: u32::from_str_radix(field(&w, "hash").trim_start_matches("0x"), 16)
                        .unwrap(),
                });
            }
            Some("volume") => {
                assert!(!w.contains(&"error"), "{line}");
                let num = |k: &str| field(&w, k).parse::<u64>().unwrap();
                let crc = u64::from_str_radix(field(&w, "crc").trim_start_matches("0x"), 16);
                r.volumes.insert(
                    w[1].to_string(),
                    [
                        num("prepare"),
                        num("setup"),
                        num("phase1"),
                        num("phase2"),
                        num("samples"),
                        num("composited"),
                        crc.unwrap(),
                        num("skipped"),
                    ],
                );
            }
            Some("cull") => {
                assert!(!w.contains(&"error"), "{line}");
                let num = |k: &str| field(&w, k).parse::<u64>().unwrap();
                let crc = u64::from_str_radix(field(&w, "crc").trim_start_matches("0x"), 16);
                r.culls.insert(
                    w[1].to_string(),
                    [
                        num("ticks"),
                        num("vertices"),
                        num("tested"),
                        num("culled"),
                        num("drawn"),
                        num("commands"),
                        num("prims_culled"),
                        num("reads"),
                        crc.unwrap(),
                    ],
                );
            }
            Some("trade") => {
                assert!(!w.contains(&"error"), "{line}");
                let num = |k: &str| field(&w, k).parse::<u64>().unwrap();
                let (tw, th) = field(&w, "tile").split_once('x').unwrap();
                r.trades.push(TradeLine {
                    tile: (tw.parse().unwrap(), th.parse().unwrap()),
                    bins: num("bins"),
                    bytes: num("bytes"),
                    crc: u32::from_str_radix(field(&w, "crc").trim_start_matches("0x"), 16)
                        .unwrap(),
                    raster_ticks: num("raster_ticks"),
                    flush_ticks: num("flush_ticks"),
                    passes: num("bin_passes"),
                });
            }
            Some("calibrate") => {
                let num = |k: &str| field(&w, k).parse::<u64>().unwrap();
                r.calibration = (num("loop_instructions"), num("ticks"));
            }
            Some("stack_used") => r.stack_used = w[1].parse().unwrap(),
            _ => {}
        }
    }
    r
}

/// Flash (`.vector_table` + `.text` + `.rodata`) and static RAM (`.data` + `.bss`) of an ELF.
/// The volume workload on the host: what the board must print.
fn host_volume() -> [tilerast_fw::volumes::VolumeRun; 4] {
    use tilerast_fw::volumes::{run, BRICK_BYTES, CELL_BYTES, VOXELS};
    let mut density = vec![0u8; VOXELS];
    let mut normals = vec![0u8; 3 * VOXELS];
    let mut bricks = vec![0u8; BRICK_BYTES];
    let mut cells = vec![0u8; CELL_BYTES];
    run(
        density.as_mut_slice().try_into().unwrap(),
        normals.as_mut_slice().try_into().unwrap(),
        bricks.as_mut_slice().try_into().unwrap(),
        cells.as_mut_slice().try_into().unwrap(),
        &mut || 0,
    )
    .unwrap()
}

/// Whether an ELF has any function of the core's volume stage (mangled
/// names hold the module path).
fn has_volume_code(elf: &Path) -> bool {
    use object::{Object, ObjectSymbol};
    let data = std::fs::read(elf).unwrap();
    let file = object::File::parse(&*data).unwrap();
    let found = file.symbols().any(|s| {
        s.name()
            .is_ok_and(|n| n.contains("8tilerast6volume") || n.contains("11tilerast_fw7volumes"))
    });
    found
}

/// Whether an ELF has any function of the core's occlusion stage.
fn has_occlusion_code(elf: &Path) -> bool {
    use object::{Object, ObjectSymbol};
    let data = std::fs::read(elf).unwrap();
    let file = object::File::parse(&*data).unwrap();
    let found = file
        .symbols()
        .any(|s| s.name().is_ok_and(|n| n.contains("8tilerast9occlusion")));
    found
}

fn sizes(elf: &Path) -> (u64, u64) {
    use object::{Object, ObjectSection};
    let data = std::fs::read(elf).unwrap();
    let file = object::File::parse(&*data).unwrap();
    let size = |names: &[&str]| -> u64 {
        file.sections()
            .filter(|s| names.contains(&s.name().unwrap_or("")))
            .map(|s| s.size())
            .sum()
    };
    (
        // (`.init.rust` and `.eh_frame`: RISC-V's `riscv-rt`.)
        size(&[
            ".vector_table",
            ".text",
            ".init.rust",
            ".rodata",
            ".eh_frame",
        ]),
        size(&[".data", ".bss", ".uninit"]),
    )
}

/// The bytes of a mesh a firmware draws.
fn mesh_bytes(scenes: &Path, name: &str) -> Vec<u8> {
    match name {
        "teapot" => std::fs::read(scenes.join("teapot.mesh")).unwrap(),
        "cube" => {
            let mut buf = [0u8; tilerast_fw::spin::CUBE_BYTES];
            tilerast_fw::spin::cube(&mut buf).unwrap();
            buf.to_vec()
        }
        other => panic!("unknown mesh {other}"),
    }
}

/// The hash the host computes for a `geom` line (the vertex stage alone).
fn host_geom_hash(scenes: &Path, l: &GeomLine) -> u32 {
    use tilerast::geometry::{Fx, Mesh, VertexSlot};
    use tilerast_fw::spin::vertex_stage;
    let bytes = mesh_bytes(scenes, &l.mesh);
    let mesh = Mesh::parse(&bytes).unwrap();
    let mut slots = vec![VertexSlot::EMPTY; mesh.vertices() as usize];
    let at = (l.frame, l.frames);
    match l.backend.as_str() {
        "f32" => vertex_stage::<f32>(&mesh, &mut slots, at, &mut || 0),
        _ => vertex_stage::<Fx>(&mesh, &mut slots, at, &mut || 0),
    }
    .unwrap()
    .2
}

/// The CRC the host computes for a `spin` frame, with the same code and no
/// bins (binning does not change output).
fn host_spin_crc(scenes: &Path, l: &SpinLine, tile: (u16, u16)) -> u32 {
    use tilerast::geometry::{Fx, Mesh, VertexSlot};
    use tilerast_fw::spin;
    let bytes = mesh_bytes(scenes, &l.mesh);
    let mesh = Mesh::parse(&bytes).unwrap();
    let mut slots = vec![VertexSlot::EMPTY; mesh.vertices() as usize];
    let mut tile_buf = tilerast::tile::Tile::new();
    let mut bins = tilerast::bin::Bins::<0, 0>::new();
    let f = match l.backend.as_str() {
        "f32" => spin::frame::<f32, 2048, 0, 0>(
            &mesh,
            &mut slots,
            &mut tile_buf,
            &mut bins,
            tile,
            l.frame,
            l.frames,
            &mut || 0,
        ),
        _ => spin::frame::<Fx, 2048, 0, 0>(
            &mesh,
            &mut slots,
            &mut tile_buf,
            &mut bins,
            tile,
            l.frame,
            l.frames,
            &mut || 0,
        ),
    };
    f.unwrap().crc
}

fn host_crc(name: &str, bytes: &[u8], tile: (u16, u16)) -> u32 {
    // Tile capacity does not change output: one generous capacity serves all.
    let mut clock = || 0;
    match name {
        // Nor do the bins: none at all here.
        "demo" => {
            scene_crc::<Demo, 2048, 0, 0>(bytes, tile, &mut clock)
                .unwrap()
                .0
        }
        "teapot" => {
            scene_crc::<Teapot, 2048, 0, 0>(bytes, tile, &mut clock)
                .unwrap()
                .0
        }
        "teapot_cull" => {
            scene_crc::<TeapotCull, 2048, 0, 0>(bytes, tile, &mut clock)
                .unwrap()
                .0
        }
        "ssd1306" => {
            scene_crc::<Ssd1306, 2048, 0, 0>(bytes, tile, &mut clock)
                .unwrap()
                .0
        }
        other => panic!("unknown scene {other}"),
    }
}

/// The CRC of the tile the translucent workload leaves, drawn on the host.
/// The host's CRC of a workload drawn in tile configuration `C`.
fn host_bench_crc<C: tilerast::config::TileConfig>(cmds: &[tilerast::command::Command]) -> u32 {
    let mut tile: tilerast::tile::Tile<128, C> = tilerast::tile::Tile::new();
    workloads::draw(&mut tile, cmds, &workloads::TEXTURES, &mut || 0).unwrap();
    workloads::tile_crc(&tile)
}

#[test]
#[ignore = "needs qemu-system-arm and the thumb targets: run `cargo xtask test`"]
fn firmware_output_is_bit_identical_to_the_host() {
    let scenes = export_scenes();
    let mut reports = vec![];
    for board in BOARDS {
        let elf = build(board, &scenes, None);
        let out = run(board, &elf);
        let mut r = parse(&out);
        check_clock(board, &r);
        // The teapots' flash images fit only the MPS2's 4 MB.
        let expect = if board == "microbit" { 2 } else { 4 };
        assert_eq!(r.scenes.len(), expect, "{out}");
        for (name, SceneLine { tile, crc, .. }) in &r.scenes {
            let bytes = std::fs::read(scenes.join(format!("{name}.bin"))).unwrap();
            let host = host_crc(name, &bytes, *tile);
            assert_eq!(
                *crc, host,
                "{board} {name}: CRC 0x{crc:08x}, host 0x{host:08x}"
            );
            println!(
                "{board:>10} {name:>8} tile {}x{}: CRC 0x{crc:08x} = host",
                tile.0, tile.1
            );
        }
        // The SSD1306 scene's trade points: the same pixels at every tile
        // size and bin capacity.
        let ssd = std::fs::read(scenes.join("ssd1306.bin")).unwrap();
        for t in &r.trades {
            let host = host_crc("ssd1306", &ssd, t.tile);
            assert_eq!(
                t.crc, host,
                "{board}: trade point {t:?} differs from the host"
            );
        }
        // Running twice gives the same counts: the measurement is deterministic.
        let again = parse(&run(board, &elf));
        assert_eq!(
            again.benches, r.benches,
            "{board}: instruction counts differ between runs"
        );
        let full = sizes(&elf);
        let full_volume = has_volume_code(&elf);
        let full_occlusion = has_occlusion_code(&elf);
        let min_elf = build(board, &scenes, Some("ssd1306"));
        // Read now: the micro:bit's later builds replace this ELF.
        let minimal = sizes(&min_elf);
        let min_volume = has_volume_code(&min_elf);
        let min_occlusion = has_occlusion_code(&min_elf);
        let min_run = parse(&run(board, &min_elf));
        assert_eq!(
            min_run.scenes["ssd1306"].crc, r.scenes["ssd1306"].crc,
            "{board}: minimal build renders differently"
        );
        // What a 1-bit display's firmware needs: 6 KB of RAM, stack included.
        let ram = minimal.1 + min_run.stack_used;
        assert!(
            ram <= 6 * 1024,
            "{board}: the SSD1306-only build takes {ram} bytes of RAM"
        );
        // The same built for size: flash against instructions.
        let small_elf = build_small(board, &scenes, Some("ssd1306"));
        let small = sizes(&small_elf);
        let small_run = parse(&run(board, &small_elf));
        assert_eq!(
            small_run.scenes["ssd1306"].crc, r.scenes["ssd1306"].crc,
            "{board}: the build for size renders differently"
        );
        let frame_instr = |run: &Report| {
            let l = &run.scenes["ssd1306"];
            ((l.raster_ticks + l.flush_ticks) as f64 * run.instr_per_tick) as u64
        };
        // (Built last: it replaces the full build's ELF.) The micro:bit's 256 KB of flash hold the scenes and workloads or
        // the rotating cube, not both: the cube is a build of its own.
        if board == "microbit" {
            let spin = parse(&run(board, &build(board, &scenes, Some("spin"))));
            r.spins.extend(spin.spins);
            r.geoms.extend(spin.geoms);
            // The workloads, too, are a build of their own there (each tile
            // configuration they measure is a copy of the draw code).
            let bench = build(board, &scenes, Some("bench"));
            let (b1, b2) = (parse(&run(board, &bench)), parse(&run(board, &bench)));
            assert_eq!(
                b1.benches, b2.benches,
                "{board}: instruction counts differ between runs"
            );
            r.benches.extend(b1.benches);
            r.bench_crcs.extend(b1.bench_crcs);
            // And the area-sampling and texturing workloads, another.
            let area = parse(&run(board, &build(board, &scenes, Some("bench_extra"))));
            r.benches.extend(area.benches);
            r.bench_crcs.extend(area.bench_crcs);
        }
        // The translucent, fast-Phong, textured and area-sampled workloads
        // leave the same bytes as on the host.
        for (name, host) in [
            (
                "gouraud_z_plane_rgb565",
                host_bench_crc::<workloads::PlaneZBench>(&TRIANGLE_CMDS),
            ),
            (
                "gouraud_z_wid_dither8_plane_rgb565",
                host_bench_crc::<workloads::PlaneZWidDitherBench>(&TRIANGLE_CMDS),
            ),
            (
                "gouraud_z_area_aa_rgb565",
                host_bench_crc::<workloads::AreaAaBench>(&workloads::AREA_AA_CMDS),
            ),
            (
                "large_blend_z_rgb565",
                host_bench_crc::<workloads::BlendBench>(&workloads::LARGE_BLEND_CMDS),
            ),
            (
                "large_phong_z_rgb565",
                host_bench_crc::<workloads::QuadBench>(&workloads::LARGE_QUAD_CMDS),
            ),
            (
                "large_tex_affine_z_rgb565",
                host_bench_crc::<workloads::TexBench<AffineTexturing>>(&workloads::LARGE_TEX_CMDS),
            ),
            (
                "large_tex_quadratic_z_rgb565",
                host_bench_crc::<workloads::TexBench<QuadraticTexturing>>(
                    &workloads::LARGE_TEX_CMDS,
                ),
            ),
            (
                "large_tex_exact_z_rgb565",
                host_bench_crc::<workloads::TexBench<ExactTexturing>>(&workloads::LARGE_TEX_CMDS),
            ),
            (
                "large_tex_quadratic_2texel_z_rgb565",
                host_bench_crc::<workloads::TexBench<QuadraticTexturing<16>>>(
                    &workloads::LARGE_TEX_CMDS,
                ),
            ),
            (
                "large_tex_quadratic_nosplit_z_rgb565",
                host_bench_crc::<workloads::TexBench<QuadraticTexturing<NEVER_SPLIT>>>(
                    &workloads::LARGE_TEX_CMDS,
                ),
            ),
        ] {
            if board == "microbit" && name.contains("plane") {
                continue; // not in its workload build (flash)
            }
            let crc = r.bench_crcs[name];
            assert_eq!(
                crc, host,
                "{board}: workload {name} CRC 0x{crc:08x} differs from the host's"
            );
            println!("{board:>10} {name}: CRC 0x{crc:08x} = host");
        }
        // The rotating mesh, frame by frame; the other back end's vertex
        // stage, hashed.
        check_spins(board, &r, &scenes, r.scenes["demo"].tile, &out);
        // The volume (not on the micro:bit: 129 KB of volume in RAM), every
        // mode bit for bit; skipping transparent bricks draws the same
        // frame and skips something; a build without it carries none of
        // the volume stage.
        if board != "microbit" {
            let host = host_volume();
            for (mode, h) in tilerast_fw::volumes::MODES.iter().zip(&host) {
                let v = r
                    .volumes
                    .get(*mode)
                    .unwrap_or_else(|| panic!("{board}: no volume {mode}:\n{out}"));
                let s = &h.stats;
                assert_eq!(
                    (v[4], v[5], v[6] as u32, v[7]),
                    (
                        s.samples as u64,
                        s.composited as u64,
                        h.crc,
                        s.skipped as u64
                    ),
                    "{board}: volume {mode} differs from the host's"
                );
                println!("{board:>10} volume {mode}: CRC 0x{:08x} = host", h.crc);
            }
            for skipping in &host[2..] {
                assert_eq!(skipping.crc, host[0].crc, "skipping changed the frame");
                assert!(skipping.stats.skipped > skipping.stats.samples / 4);
            }
            // The cells, finer than the bricks, skip more (counting the
            // samples outside their box, never walked).
            let unwalked = host[0].stats.samples - host[3].stats.samples;
            assert!(host[3].stats.skipped + unwalked > host[2].stats.skipped);
            assert!(full_volume, "{board}: the full build has no volume code?");
            assert!(
                !min_volume,
                "{board}: a build without the volume feature carries volume code"
            );
        }
        // The culled city (not on the micro:bit), every mode bit for bit as
        // the host's, and every mode's frames equal to the unculled ones.
        if board != "microbit" {
            let mut slots =
                vec![tilerast::geometry::VertexSlot::EMPTY; tilerast_fw::city::FW_SLOTS];
            for mode in tilerast::occlusion::CullMode::ALL {
                let h = tilerast_fw::city::run_fw(mode, &mut slots, &mut || 0).unwrap();
                let c = r
                    .culls
                    .get(mode.name())
                    .unwrap_or_else(|| panic!("{board}: no cull {}:\n{out}", mode.name()));
                let s = &h.stats;
                assert_eq!(
                    &c[1..],
                    &[
                        h.vertices as u64,
                        s.boxes_tested as u64,
                        s.nodes_culled as u64,
                        s.objects_drawn as u64,
                        s.commands as u64,
                        s.prims_culled as u64,
                        s.cost.reads,
                        h.crc as u64
                    ],
                    "{board}: cull {} differs from the host's",
                    mode.name()
                );
                assert_eq!(
                    c[8],
                    r.culls["none"][8],
                    "{board}: cull {} is not exact",
                    mode.name()
                );
                println!(
                    "{board:>10} cull {}: CRC 0x{:08x} = host = unculled",
                    mode.name(),
                    h.crc
                );
            }
            assert!(
                full_occlusion,
                "{board}: the full build has no occlusion code?"
            );
            assert!(
                !min_occlusion,
                "{board}: a build without the cull feature carries occlusion code"
            );
        }
        reports.push(BoardResult {
            full,
            minimal,
            minimal_stack: min_run.stack_used,
            minimal_frame: frame_instr(&min_run),
            small,
            small_stack: small_run.stack_used,
            small_frame: frame_instr(&small_run),
            report: r,
        });
    }
    // Cortex-M0-class code (`thumbv6m`) on the MPS2 board: the rotating
    // teapot, which the micro:bit cannot hold (an RP2040-class workload),
    // in fixed point, bit for bit as the host's.
    let elf = build_for(
        "mps2-an386",
        Some("thumbv6m-none-eabi"),
        &scenes,
        Some("spin"),
        false,
    );
    let out = run("mps2-an386", &elf);
    let mut v6 = parse(&out);
    v6.board = "mps2-an386, ARMv6-M code".into();
    let tile = reports[0].report.scenes["demo"].tile;
    check_spins("mps2-an386 (thumbv6m)", &v6, &scenes, tile, &out);
    if let Some(path) = std::env::var_os("TILERAST_REPORT") {
        std::fs::write(&path, report(&reports, &v6)).unwrap();
        println!("wrote {}", Path::new(&path).display());
    }
}

/// The size of an exported scene the firmware embeds.
fn scene_bytes(name: &str) -> u64 {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("scenes")
        .join(format!("{name}.bin"));
    std::fs::metadata(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .len()
}

/// The QEMU boards, one per instruction set, in the report's column order:
/// ARMv7E-M, ARMv8-M Mainline, RV32IMAC, ARMv6-M.
const BOARDS: [&str; 4] = ["mps2-an386", "mps2-an505", "riscv-virt", "microbit"];

/// Asserts the board's clock counted its calibration loop (`2 n`
/// instructions, `n` iterations of two) as its stated instructions per
/// tick say: to a tick, beside the few instructions around the loop.
fn check_clock(board: &str, r: &Report) {
    let (n, ticks) = r.calibration;
    assert!(n > 0, "{board}: no calibrate line");
    let counted = ticks as f64 * r.instr_per_tick;
    let slack = r.instr_per_tick + 32.0;
    assert!(
        (counted - n as f64).abs() <= slack,
        "{board}: a loop of {n} instructions took {ticks} ticks = {counted} instructions \
         at {} a tick",
        r.instr_per_tick
    );
    println!(
        "{board:>10} clock: {n}-instruction loop = {ticks} ticks x {} = {counted}",
        r.instr_per_tick
    );
}

/// Asserts a board's rotating-mesh frames and vertex stages equal the
/// host's, frame by frame.
fn check_spins(board: &str, r: &Report, scenes: &Path, spin_tile: (u16, u16), out: &str) {
    assert!(
        r.spins.len() >= 8 && r.geoms.len() >= 4,
        "{board}: spin frames missing:\n{out}"
    );
    for l in &r.geoms {
        let host = host_geom_hash(scenes, l);
        assert_eq!(
            l.hash, host,
            "{board} geom {} {} frame {}/{}: hash 0x{:08x}, host 0x{host:08x}",
            l.mesh, l.backend, l.frame, l.frames, l.hash
        );
    }
    for l in &r.spins {
        let host = host_spin_crc(scenes, l, spin_tile);
        assert_eq!(
            l.crc, host,
            "{board} spin {} {} frame {}/{}: CRC 0x{:08x}, host 0x{host:08x}",
            l.mesh, l.backend, l.frame, l.frames, l.crc
        );
    }
    println!(
        "{board:>10} spin: {} frames of {} ({}), {} vertex stages ({}): every CRC and hash = host",
        r.spins.len(),
        r.spins[0].mesh,
        r.spins[0].backend,
        r.geoms.len(),
        r.geoms[0].backend
    );
}

/// A board's report with the sizes of its full and minimal builds.
struct BoardResult {
    report: Report,
    /// (flash, static RAM) of the build with every feature.
    full: (u64, u64),
    /// (flash, static RAM) of the build with only what the SSD1306 scene needs.
    minimal: (u64, u64),
    minimal_stack: u64,
    /// Instructions of its SSD1306 frame.
    minimal_frame: u64,
    /// The same built for size (`opt-level = "s"`).
    small: (u64, u64),
    small_stack: u64,
    small_frame: u64,
}

/// Markdown rows: for each `(label, bench, elements)`, every board's
/// instructions per element.
fn table_rows(boards: &[&Report], rows: &[(&str, &str, u64)]) -> String {
    let mut md = String::new();
    for (label, key, n) in rows {
        md += &format!("| {label} |");
        for b in boards {
            md += &match b.benches.get(*key) {
                Some(t) => format!(" {:.1} |", *t as f64 * b.instr_per_tick / *n as f64),
                // A workload a board's build leaves out (its flash).
                None => " — |".into(),
            };
        }
        md += "\n";
    }
    md
}

fn report(reports: &[BoardResult], v6: &Report) -> String {
    let tri_px = workloads::covered_pixels(&TRIANGLE_CMDS, workloads::SIDE).unwrap();
    let fill_px = workloads::covered_pixels(&FILL_CMDS, workloads::SIDE).unwrap();
    let eg_px = workloads::eg_covered_pixels(&TRIANGLE_CMDS);
    let large_px = workloads::covered_pixels(&LARGE_TRIANGLE_CMDS, workloads::SIDE).unwrap();
    let mut md = String::from("# Instructions per pixel on emulated Cortex-M and RISC-V\n\n");
    md += "Generated by `cargo xtask report` (the firmware test with `TILERAST_REPORT`). \
           QEMU runs each firmware with `-icount shift=0` (one instruction per virtual \
           nanosecond). On Arm, SysTick counts the core clock, so one tick is a fixed number \
           of instructions: 40 on `mps2-an386` (Cortex-M4F, ARMv7E-M, 25 MHz), 50 on \
           `mps2-an505` (Cortex-M33, ARMv8-M Mainline, 20 MHz), 62.5 on `microbit` \
           (Cortex-M0, ARMv6-M, 16 MHz). On `riscv-virt` (RV32IMAC) `minstret` counts retired \
           instructions: one a tick. Each run first times a loop of known length (2 M \
           instructions) with the same clock, and the test asserts it counts right to a tick \
           (the clock table below). Whole workloads and whole frames are timed, never single pixels; per-pixel figures \
           divide by the pixels the workload rasterizes (counted on the host: covered pixels \
           summed over commands, overdraw included). Two runs give identical counts (asserted).\n\n";
    md += &format!(
        "Workloads: one {s}x{s} tile; {t} small Gouraud triangles ({tri_px} pixels in \
         all, about 10 each, as a mesh on a small screen; setup included); {l} large Gouraud \
         triangles, pairs that each cover the tile ({large_px} pixels, each stored: what a \
         span costs per pixel, setup and rows included); {f} full-tile flat fills ({fill_px} pixels). \
         `embedded-graphics` fills the same triangles flat ({eg_px} pixels by its own rules).\n\n",
        s = workloads::SIDE, t = workloads::TRIANGLES, f = workloads::FILLS,
        l = workloads::LARGE_TRIANGLES
    );
    let boards: Vec<&Report> = reports.iter().map(|r| &r.report).collect();
    md += "| board | clock | instructions a tick | a loop of 2 M instructions, counted |\n\
           | --- | --- | ---: | ---: |\n";
    for b in &boards {
        let clock = if b.board.starts_with("riscv") {
            "`minstret`"
        } else {
            "SysTick"
        };
        md += &format!(
            "| {} | {clock} | {} | {:.0} |\n",
            b.board,
            b.instr_per_tick,
            b.calibration.1 as f64 * b.instr_per_tick
        );
    }
    md += "\n| workload | ";
    md += &boards
        .iter()
        .map(|b| format!("{} instr/px", b.board))
        .collect::<Vec<_>>()
        .join(" | ");
    md += " |\n| --- |";
    md += &" ---: |".repeat(boards.len());
    md += "\n";
    let rows = [
        ("flat fill, RGB565", "fill_rgb565", fill_px),
        ("Gouraud, RGB565", "gouraud_rgb565", tri_px),
        ("Gouraud + Z", "gouraud_z_rgb565", tri_px),
        (
            "Gouraud + Z + edge AA (eq. 8) on every edge",
            "gouraud_z_edge_aa_rgb565",
            tri_px,
        ),
        (
            "Gouraud + Z + area sampling (α, seed 001 §IV.5) on every edge",
            "gouraud_z_area_aa_rgb565",
            tri_px,
        ),
        ("Gouraud + Z + window ID", "gouraud_z_wid_rgb565", tri_px),
        (
            "Gouraud + Z + window ID + 8x8 dither",
            "gouraud_z_wid_dither8_rgb565",
            tri_px,
        ),
        (
            "Gouraud + Z, plane contract (`PlaneContract`)",
            "gouraud_z_plane_rgb565",
            tri_px,
        ),
        (
            "Gouraud + Z + window ID + 8x8 dither, plane contract",
            "gouraud_z_wid_dither8_plane_rgb565",
            tri_px,
        ),
        (
            "embedded-graphics `Triangle` fill (flat)",
            "eg_triangle_rgb565",
            eg_px,
        ),
        (
            "large triangles: Gouraud, RGB565",
            "large_gouraud_rgb565",
            large_px,
        ),
        (
            "large triangles: Gouraud + Z",
            "large_gouraud_z_rgb565",
            large_px,
        ),
        (
            "large triangles: Gouraud + Z + window ID + 8x8 dither",
            "large_gouraud_z_wid_dither8_rgb565",
            large_px,
        ),
        (
            "large triangles: Gouraud + Z, alpha-blended (per-vertex α)",
            "large_blend_z_rgb565",
            large_px,
        ),
        (
            "large triangles: fast Phong (quadratic, seed 001 §IV.2) + Z",
            "large_phong_z_rgb565",
            large_px,
        ),
        (
            "large triangles: textured (16x16 RGB565, nearest, q 4:1) + Z, affine",
            "large_tex_affine_z_rgb565",
            large_px,
        ),
        (
            "the same, perspective by quadratic interpolation along the span (seed 001 §IV.3)",
            "large_tex_quadratic_z_rgb565",
            large_px,
        ),
        (
            "the same, perspective by division at every pixel",
            "large_tex_exact_z_rgb565",
            large_px,
        ),
        (
            "the same, quadratic within two texels (`QuadraticTexturing<16>`)",
            "large_tex_quadratic_2texel_z_rgb565",
            large_px,
        ),
        (
            "the same, quadratic never split (`QuadraticTexturing<NEVER_SPLIT>`, the seed's 32-px segments)",
            "large_tex_quadratic_nosplit_z_rgb565",
            large_px,
        ),
        (
            "exact Phong's per-pixel arithmetic alone (normalise + light + pack, no raster, no Z), f32",
            "exact_phong_f32_rgb565",
            large_px,
        ),
        (
            "the same in I16F16 fixed point",
            "exact_phong_fixed_rgb565",
            large_px,
        ),
    ];
    md += &table_rows(&boards, &rows);
    md += "| **ratio** alpha-blended / opaque (large, Gouraud + Z; target ≤ 1.5 on the M4) |";
    for b in &boards {
        let r =
            b.benches["large_blend_z_rgb565"] as f64 / b.benches["large_gouraud_z_rgb565"] as f64;
        md += &format!(" {r:.2} |");
    }
    md += "\n";
    md += "| **ratio** fast Phong / Gouraud (large, + Z; target ≤ 1.5 on the M4) |";
    for b in &boards {
        let r =
            b.benches["large_phong_z_rgb565"] as f64 / b.benches["large_gouraud_z_rgb565"] as f64;
        md += &format!(" {r:.2} |");
    }
    md += "\n";
    md += "| **ratio** quadratic / affine texturing (target ≤ 1.3) |";
    for b in &boards {
        let r = b.benches["large_tex_quadratic_z_rgb565"] as f64
            / b.benches["large_tex_affine_z_rgb565"] as f64;
        md += &format!(" {r:.2} |");
    }
    md += "\n";
    md += "| **ratio** quadratic within two texels / affine; never split / affine |";
    for b in &boards {
        let affine = b.benches["large_tex_affine_z_rgb565"] as f64;
        let two = b.benches["large_tex_quadratic_2texel_z_rgb565"] as f64 / affine;
        let never = b.benches["large_tex_quadratic_nosplit_z_rgb565"] as f64 / affine;
        md += &format!(" {two:.2}; {never:.2} |");
    }
    md += "\n";
    md += "| **ratio** quadratic / exact texturing (target ≤ 0.5 on the M0) |";
    for b in &boards {
        let r = b.benches["large_tex_quadratic_z_rgb565"] as f64
            / b.benches["large_tex_exact_z_rgb565"] as f64;
        md += &format!(" {r:.2} |");
    }
    md += "\n";
    md += "| **ratio** embedded-graphics flat / ours Gouraud |";
    for b in &boards {
        let ours = b.benches["gouraud_rgb565"] as f64 / tri_px as f64;
        let eg = b.benches["eg_triangle_rgb565"] as f64 / eg_px as f64;
        md += &format!(" {:.2} |", eg / ours);
    }
    let steps = workloads::line_steps(&LINE_CMDS);
    md += &format!(
        "\n\n## Lines\n\n{n} lines across the tile in every direction ({steps} steps along \
         their major axes; the Wu lines touch the end cells too). Per step: Bresenham writes one \
         pixel, Wu blends two (read, blend, write).\n\n| lines | ",
        n = workloads::LINES
    );
    md += &boards
        .iter()
        .map(|b| format!("{} instr/step", b.board))
        .collect::<Vec<_>>()
        .join(" | ");
    md += " |\n| --- |";
    md += &" ---: |".repeat(boards.len());
    md += "\n";
    md += &table_rows(
        &boards,
        &[
            ("Bresenham, RGB565", "bresenham_rgb565", steps),
            ("two-point (Wu) antialiased, RGB565", "wu_rgb565", steps),
            (
                "embedded-graphics `Line` (1 px stroke)",
                "eg_line_rgb565",
                steps,
            ),
        ],
    );
    md += "\n\n## Whole frames\n\n| board | scene | tile | raster instr/px | flush instr/px | total instr/frame | CRC |\n| --- | --- | --- | ---: | ---: | ---: | --- |\n";
    for b in &boards {
        for (name, l) in &b.scenes {
            let k = b.instr_per_tick;
            md += &format!(
                "| {} | {name} | {}x{} | {:.0} | {:.1} | {:.1} M | `0x{:08x}` |\n",
                b.board,
                l.tile.0,
                l.tile.1,
                l.raster_ticks as f64 * k / l.pixels as f64,
                l.flush_ticks as f64 * k / l.pixels as f64,
                (l.raster_ticks + l.flush_ticks) as f64 * k / 1e6,
                l.crc
            );
        }
    }
    md += "\n## Where a frame goes (phase counters)\n\nEach scene is rendered again *until* each phase \
           (`Frame::render_until`: the work of that phase and every one before it, nothing after), \
           timed by SysTick; a phase's cost is the difference with the one before. *Bin*: the \
           binning passes (each decodes every command); *decode*: reading each tile's binned \
           commands in place; *setup*: triangle setup; *traverse*: the rows each triangle covers; \
           *span and rest*: per-row restart, span loops, fragment tests and stores, the other \
           commands. *Flush*: the label and the flush, from the frame above. \
           The demo draws its mesh under the plane contract: the partial renders reach its \
           triangles as commands (the exact contract's decode, setup and traversal), the whole \
           frame through the fused mesh path, which does all three in one routine, so its *span \
           and rest* is only what the whole frame saves or adds beyond them. Millions of instructions.\n\n\
           | board | scene | bin | clear | decode | setup | traverse | span and rest | flush | total | bin passes | bin entries (peak) | tiles unbinned | (tile, command) pairs |\n\
           | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for b in &boards {
        for (name, p) in &b.phases {
            let k = b.instr_per_tick / 1e6;
            let l = &b.scenes[name];
            let d = |i: usize| p[i].saturating_sub(if i == 0 { 0 } else { p[i - 1] }) as f64 * k;
            let bins = b.bins[name];
            md += &format!(
                "| {} | {name} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} |\n",
                b.board,
                d(0),
                d(1),
                d(2),
                d(3),
                d(4),
                d(5),
                l.flush_ticks as f64 * k,
                (l.raster_ticks + l.flush_ticks) as f64 * k,
                bins[0],
                bins[1],
                bins[2],
                bins[3]
            );
        }
    }
    let mut spin_boards = boards.clone();
    spin_boards.insert(1, v6);
    md += &spin_section(&spin_boards);
    for b in &boards {
        let (Some(out), Some(inp)) = (b.anim.get("output"), b.anim.get("input")) else {
            continue;
        };
        let [frames, tiles, _, _, full, _, _] = *out;
        let per = |v: u64| v / frames;
        let instr = |t: u64| t as f64 * b.instr_per_tick / frames as f64 / 1e6;
        md += &format!(
            "\n## Partial updates ({})\n\nAn animated gauge (`targets/common/src/anim.rs`): 12 Gouraud \
             wedges and a needle that turns every frame, 240x240 RGB565 + Z in 64x32 tiles, {frames} \
             frames. *Output*: every tile is drawn, hashed (`Damage::changed`) and sent only when its \
             pixels changed. *Input*: each tile hashes its binned commands first and is drawn and sent \
             only when they changed (`Frame::render_changed`). Instructions: binning, hashing and \
             drawing, a frame.\n\n\
             | | tiles drawn | tiles sent | bytes sent to the panel | bytes a frame | instructions a frame |\n\
             | --- | ---: | ---: | ---: | ---: | ---: |\n\
             | full refresh | {tiles} | {tiles} | {full} | {} | — |\n",
            b.board,
            per(full),
        );
        for (name, r) in [("output", out), ("input", inp)] {
            let [_, _, drawn, sent, _, bytes, ticks] = *r;
            md += &format!(
                "| partial updates, {name} | {drawn} | {sent} | {bytes} | {} | {:.2} M |\n",
                per(bytes),
                instr(ticks)
            );
        }
        md += &format!(
            "\nBytes sent: **{:.1}%** (output) and **{:.1}%** (input) of a full refresh; \
             instructions a frame: input **{:.2}x** output.\n",
            100.0 * out[5] as f64 / full as f64,
            100.0 * inp[5] as f64 / full as f64,
            inp[6] as f64 / out[6] as f64
        );
    }
    for b in &boards {
        if b.volumes.is_empty() {
            continue;
        }
        use tilerast_fw::volumes::{VOL_SCREEN, VOL_SIDE, VOL_SLICES};
        let k = |t: u64| t as f64 * b.instr_per_tick;
        md += &format!(
            "\n## Volume rendering ({})\n\nThe seed-002 workload (`targets/common/src/volumes.rs`): the \
             procedural sphere, {VOL_SIDE}^3, made and its normals quantised on the device, {VOL_SLICES} \
             view-aligned slices into a {VOL_SCREEN}x{VOL_SCREEN} RGB565 frame (4x4 dither, 32x32 tiles, \
             normal plane 14 KB). Phase I: slice, classify, composite; phase II: shade. \
             `normal_bricks` is normal blending skipping the samples of 4-cell bricks the transfer \
             function makes transparent (1 KB of brick ranges), `normal_cells` the samples of the \
             cells it makes transparent (4 KB, a bit a cell, made for the transfer function), and \
             walks none outside the box of the visible cells; both the same frame as \
             `normal_blending`. *Samples*: those each mode walks (in the volume, nearer than the \
             depth plane); *per frame sample*: phase I over the frame's samples (`normal_blending`'s \
             count, the same frame in every mode); *per walked sample*: over the mode's own. \
             Every mode's frames equal the host's (CRC). `reports/volume.md` has the host's size \
             series.\n\n\
             | mode | samples | skipped | blended | phase I instr | per frame sample | per walked sample | phase II instr | per pixel | total instr |\n\
             | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
            b.board
        );
        let px = (VOL_SCREEN as f64).powi(2);
        let frame_samples = b.volumes.get("normal_blending").map_or(1, |v| v[4].max(1)) as f64;
        let mut prep = (0, 0);
        for (mode, v) in &b.volumes {
            if *mode == "normal_blending" {
                prep = (v[0], v[1]);
            }
            md += &format!(
                "| {mode} | {} | {} | {} | {:.0} | {:.1} | {:.1} | {:.0} | {:.1} | {:.0} |\n",
                v[4],
                v[7],
                v[5],
                k(v[2]),
                k(v[2]) / frame_samples,
                k(v[2]) / v[4].max(1) as f64,
                k(v[3]),
                k(v[3]) / px,
                k(v[1] + v[2] + v[3])
            );
        }
        md += &format!(
            "\nOnce: making the sphere and its normals {:.2} M instructions; slicing {:.0} instructions a frame.\n",
            k(prep.0) / 1e6,
            k(prep.1)
        );
    }
    for b in &boards {
        if b.culls.is_empty() {
            continue;
        }
        use tilerast_fw::city::{FW_CITY, FW_FRAMES, FW_SCREEN};
        let k = |t: u64| t as f64 * b.instr_per_tick;
        md += &format!(
            "\n## Occlusion culling ({})\n\nThe seed-004 workload (`targets/common/src/city.rs`): a city of \
             {} x {} buildings (faces subdivided {}x{}) and its ground, walked for {FW_FRAMES} frames by a \
             camera down its middle street, {FW_SCREEN}x{FW_SCREEN} RGB565 + 16-bit Z in 48x48 tiles, \
             8x8 depth blocks; geometry, culling and raster counted, flush not. Every mode's frames \
             equal the unculled frames and the host's (CRC). `reports/cull.md` has the host's scenes.\n\n\
             | mode | instructions / frame | vs none | vertices | box tests | nodes culled | objects drawn | commands | primitives culled | depth reads |\n\
             | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
            b.board, FW_CITY.side, FW_CITY.side, FW_CITY.sub, FW_CITY.sub
        );
        let none = k(b.culls.get("none").map_or(0, |c| c[0]));
        for mode in tilerast::occlusion::CullMode::ALL {
            let Some(c) = b.culls.get(mode.name()) else {
                continue;
            };
            md += &format!(
                "| {} | {:.0} | {:.2} | {} | {} | {} | {} | {} | {} | {} |\n",
                mode.name(),
                k(c[0]) / FW_FRAMES as f64,
                k(c[0]) / none.max(1.0),
                c[1],
                c[2],
                c[3],
                c[4],
                c[5],
                c[6],
                c[7]
            );
        }
        use tilerast::occlusion::CullMode;
        let of = |m: CullMode| b.culls.get(m.name()).map(|c| k(c[0]));
        if let (Some(sp), Some(sw), Some(chc)) = (
            of(CullMode::SinglePass),
            of(CullMode::StopAndWait),
            of(CullMode::Chc),
        ) {
            md += &format!(
                "
The seed's Table 1 form, from these exact counts: the single pass takes {:.1}% fewer \
                 instructions than stop-and-wait and {:.1}% fewer than CHC (the seed: 14–44% and 13–25%).\n",
                100.0 * (1.0 - sp / sw.max(1.0)),
                100.0 * (1.0 - sp / chc.max(1.0)),
            );
        }
    }
    for b in &boards {
        if b.trades.is_empty() {
            continue;
        }
        md += &format!(
            "\n## SSD1306: RAM against instructions ({})\n\nThe 128x64 1-bit scene (`scenes/ssd1306.toml`: \
             a mesh, Z, 4x4 dither) rendered with each tile height and bin capacity; *RAM* is the tile \
             (1-bit colour + 16-bit Z) and the bins, the stack's other ~1.2 KB aside. Every point's \
             CRC equals the host's. The firmware renders the scene in the first row's configuration \
             (one SSD1306 page a tile, 224 bin entries): the SSD1306-only build's RAM below.\n\n\
             | tile | bin entries | RAM (tile + bins) | binning passes | raster + flush instructions | × fastest |\n\
             | --- | ---: | ---: | ---: | ---: | ---: |\n",
            b.board
        );
        let cost = |t: &TradeLine| (t.raster_ticks + t.flush_ticks) as f64 * b.instr_per_tick;
        let best = b.trades.iter().map(cost).fold(f64::INFINITY, f64::min);
        for t in &b.trades {
            md += &format!(
                "| {}x{} | {} | {} | {} | {:.2} M | {:.2} |\n",
                t.tile.0,
                t.tile.1,
                t.bins,
                t.bytes,
                t.passes,
                cost(t) / 1e6,
                cost(t) / best
            );
        }
    }
    md += "\n## Flash and RAM\n\nFlash is `.vector_table` + `.text` + `.rodata` (the scenes are in `.rodata`); \
           static RAM is `.data` + `.bss`; the stack high-water mark is measured by the firmware \
           (`cortex-m-rt`'s `paint-stack` on Arm; the RISC-V port paints its own). *Full*: both scenes and the workloads (on the micro:bit \
           both scenes: its workloads and the rotating cube are builds of their own); *SSD1306 only*: \
           the features one 1-bit scene needs (`--no-default-features --features ssd1306`), of whose \
           flash the scene itself (`ssd1306.bin`, a mesh in the wire format) is the stated part; its \
           RAM is static RAM + stack peak (target: 6 KB, asserted); *for size*: the same in cargo \
           profile `small` (`opt-level = \"s\"`; the micro:bit's release builds are already). \
           *SSD1306 frame*: the scene's raster and flush instructions.\n\n\
           | board | build | flash bytes | of which scene data | static RAM bytes | stack peak bytes | SSD1306 frame instructions |\n\
           | --- | --- | ---: | ---: | ---: | ---: | ---: |\n";
    let ssd_bytes = scene_bytes("ssd1306");
    for r in reports {
        let b = &r.report;
        md += &format!(
            "| {} | full | {} | — | {} | {} | — |\n",
            b.board, r.full.0, r.full.1, b.stack_used
        );
        md += &format!(
            "| {} | SSD1306 only | {} | {ssd_bytes} | {} | {} | {:.2} M |\n",
            b.board,
            r.minimal.0,
            r.minimal.1,
            r.minimal_stack,
            r.minimal_frame as f64 / 1e6
        );
        md += &format!(
            "| {} | SSD1306 only, for size | {} | {ssd_bytes} | {} | {} | {:.2} M |\n",
            b.board,
            r.small.0,
            r.small.1,
            r.small_stack,
            r.small_frame as f64 / 1e6
        );
    }
    md
}

/// The geometry stage on the device: per board, mesh and back end, the
/// vertex stage and the raster per frame.
fn spin_section(boards: &[&Report]) -> String {
    let mut md = String::from(
        "\n## Geometry on the device: a rotating mesh\n\n\
         `targets/common/src/spin.rs`: each frame the geometry stage (`tilerast::geometry::Scene`) \
         transforms the mesh (read in place from flash), culls back faces, lights the vertices \
         visible triangles use (ambient + Lambert, one light) into the vertex cache, and the frame \
         pipeline bins it (reading the vertex cache, no command built) and draws each triangle \
         straight from the cache into the tile under the plane contract (`PlaneContract`: one \
         reciprocal a triangle, `tilerast::tile`'s mesh path) at 240x240, RGB565 + Z16, in tiles \
         of the demo's size (64x32 = 8 KB on the Cortex-M4, 32x32 on the M0). *ARMv6-M code*: \
         the teapot built for `thumbv6m-none-eabi` (Cortex-M0 class, fixed point, no FPU) and \
         run on the MPS2 board, whose RAM and flash hold a mesh the micro:bit cannot (an \
         RP2040-class workload): the same instructions an M0 runs. One full turn \
         about y, tilted 20°. \
         Every frame's CRC equals the host's (asserted). Millions of instructions per frame, \
         averaged over the frames; per vertex = vertex stage / vertices. *Bin + raster*: binning \
         and drawing the tiles; the CRC flush (handing each finished tile to the CRC) is timed \
         apart, as the C++ peers' figures have none; *total* is the three, *without flush* the \
         first two.\n\n\
         | board | mesh | back end | frames | vertex stage | instr/vertex | bin + raster | CRC flush | total per frame | without flush | front triangles | lit vertices |\n\
         | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for b in boards {
        let mut keys: Vec<(String, String)> = b
            .spins
            .iter()
            .map(|l| (l.mesh.clone(), l.backend.clone()))
            .collect();
        keys.dedup();
        for (mesh, backend) in keys {
            let ls: Vec<&SpinLine> = b
                .spins
                .iter()
                .filter(|l| l.mesh == mesh && l.backend == backend)
                .collect();
            let n = ls.len() as f64;
            let k = b.instr_per_tick;
            let avg =
                |f: &dyn Fn(&SpinLine) -> u64| ls.iter().map(|l| f(l) as f64).sum::<f64>() / n;
            let vt = avg(&|l| l.vertex_ticks) * k;
            let rt = avg(&|l| l.raster_ticks) * k;
            let ft = avg(&|l| l.flush_ticks) * k;
            md += &format!(
                "| {} | {mesh} | {backend} | {} | {:.2} M | {:.0} | {:.2} M | {:.2} M | **{:.2} M** | **{:.2} M** | {:.0} | {:.0} |\n",
                b.board,
                ls.len(),
                vt / 1e6,
                vt / avg(&|l| l.vertices),
                rt / 1e6,
                ft / 1e6,
                (vt + rt + ft) / 1e6,
                (vt + rt) / 1e6,
                avg(&|l| l.front),
                avg(&|l| l.lit),
            );
        }
        if let Some(g) = b.geoms.first() {
            let n = b.geoms.len() as f64;
            let vt =
                b.geoms.iter().map(|l| l.vertex_ticks as f64).sum::<f64>() / n * b.instr_per_tick;
            md += &format!(
                "| {} | {} | {} (vertex stage only) | {} | {:.2} M | {:.0} | — | — | — | — | — | — |\n",
                b.board,
                g.mesh,
                g.backend,
                b.geoms.len(),
                vt / 1e6,
                vt / g.vertices as f64,
            );
        }
    }
    md
}
