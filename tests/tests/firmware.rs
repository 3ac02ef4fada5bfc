//! Bit-identical output on x86-64, Cortex-M0 and Cortex-M4: builds each QEMU
//! firmware under `targets/`, runs it under `qemu-system-arm -icount shift=0`,
//! and asserts that the CRC32 of every scene's pixel stream equals the one
//! the host computes with the same code. With `TILERAST_REPORT=path` it also
//! writes the cost report (instructions per pixel, flash, RAM, stack).
//!
//! Needs `qemu-system-arm` and the thumb targets, so it is `#[ignore]`d in a
//! plain `cargo test`; `cargo xtask test` installs both and runs it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command as Process;
use tilerast_fw::report::{scene_crc, Demo, SceneKind, Ssd1306, Teapot};
use tilerast_fw::workloads::{self, FILL_CMDS, LINE_CMDS, TRIANGLE_CMDS};
use tilerast_sim::Scene;
use tilerast_tests::{repo, scene};

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
    scenes: BTreeMap<String, SceneLine>,
    benches: BTreeMap<String, u64>,
    /// Per scene: ticks until each phase (bin, clear, decode, setup, traverse, all).
    phases: BTreeMap<String, [u64; 6]>,
    /// The animated gauge: (frames, tiles, sent tiles, bytes full, bytes sent, ticks).
    anim: Option<[u64; 6]>,
    /// Per scene: (bin passes, bin peak, unbinned tiles, replayed).
    bins: BTreeMap<String, [u64; 4]>,
    stack_used: u64,
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
            }
            Some("phases") => {
                assert!(!w.contains(&"error"), "{line}");
                let k = ["bin", "clear", "decode", "setup", "traverse", "all"]
                    .map(|k| field(&w, k).parse::<u64>().unwrap());
                r.phases.insert(w[1].to_string(), k);
            }
            Some("anim") => {
                assert!(!w.contains(&"error"), "{line}");
                r.anim = Some(
                    [
                        "frames",
                        "tiles",
                        "sent_tiles",
                        "bytes_full",
                        "bytes_sent",
                        "ticks",
                    ]
                    .map(|k| field(&w, k).parse::<u64>().unwrap()),
                );
            }
            Some("stack_used") => r.stack_used = w[1].parse().unwrap(),
            _ => {}
        }
    }
    r
}

/// Exports the demo scenes as firmware flash images; returns their folder.
fn export_scenes() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scenes");
    std::fs::create_dir_all(&dir).unwrap();
    for name in [Demo::NAME, Teapot::NAME, Ssd1306::NAME] {
        let s = Scene::load(scene(&format!("{name}.toml"))).unwrap();
        std::fs::write(dir.join(format!("{name}.bin")), s.encode().unwrap()).unwrap();
    }
    dir
}

fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

/// Builds a board's firmware with `features` and returns the ELF path.
fn build(board: &str, scenes: &Path, features: Option<&str>) -> PathBuf {
    let dir = repo().join("targets").join(board);
    let mut cmd = Process::new(cargo());
    cmd.current_dir(&dir)
        .env("TILERAST_SCENES", scenes)
        .args(["build", "--release", "--quiet"]);
    if let Some(f) = features {
        cmd.args(["--no-default-features", "--features", f]);
    }
    let st = cmd.status().expect("cargo");
    assert!(st.success(), "building {board} firmware failed");
    let triple = if board == "microbit" {
        "thumbv6m-none-eabi"
    } else {
        "thumbv7em-none-eabihf"
    };
    dir.join("target")
        .join(triple)
        .join("release")
        .join(format!("tilerast-{board}"))
}

/// Runs a firmware ELF under QEMU with the runner its `.cargo/config.toml` names.
fn run(board: &str, elf: &Path) -> String {
    let config = std::fs::read_to_string(
        repo()
            .join("targets")
            .join(board)
            .join(".cargo/config.toml"),
    )
    .unwrap();
    let runner = config
        .lines()
        .find_map(|l| l.strip_prefix("runner = "))
        .expect("runner")
        .trim_matches('"');
    let mut words = runner.split_whitespace();
    let out = Process::new(words.next().unwrap())
        .args(words)
        .arg(elf)
        .output()
        .expect("qemu-system-arm (installed by `cargo xtask test`)");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{board} exited with {}:\n{text}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

/// Flash (`.vector_table` + `.text` + `.rodata`) and static RAM (`.data` + `.bss`) of an ELF.
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
        size(&[".vector_table", ".text", ".rodata"]),
        size(&[".data", ".bss", ".uninit"]),
    )
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
        "ssd1306" => {
            scene_crc::<Ssd1306, 2048, 0, 0>(bytes, tile, &mut clock)
                .unwrap()
                .0
        }
        other => panic!("unknown scene {other}"),
    }
}

#[test]
#[ignore = "needs qemu-system-arm and the thumb targets: run `cargo xtask test`"]
fn firmware_output_is_bit_identical_to_the_host() {
    let scenes = export_scenes();
    let mut reports = vec![];
    for board in ["mps2-an386", "microbit"] {
        let elf = build(board, &scenes, None);
        let out = run(board, &elf);
        let r = parse(&out);
        // The teapot's flash image fits only the MPS2's 4 MB.
        let expect = if board == "microbit" { 2 } else { 3 };
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
        // Running twice gives the same counts: the measurement is deterministic.
        let again = parse(&run(board, &elf));
        assert_eq!(
            again.benches, r.benches,
            "{board}: instruction counts differ between runs"
        );
        let full = sizes(&elf);
        let min_elf = build(board, &scenes, Some("ssd1306"));
        let min_run = parse(&run(board, &min_elf));
        assert_eq!(
            min_run.scenes["ssd1306"].crc, r.scenes["ssd1306"].crc,
            "{board}: minimal build renders differently"
        );
        reports.push(BoardResult {
            full,
            minimal: sizes(&min_elf),
            minimal_stack: min_run.stack_used,
            report: r,
        });
    }
    if let Some(path) = std::env::var_os("TILERAST_REPORT") {
        std::fs::write(&path, report(&reports)).unwrap();
        println!("wrote {}", Path::new(&path).display());
    }
}

/// A board's report with the sizes of its full and minimal builds.
struct BoardResult {
    report: Report,
    /// (flash, static RAM) of the build with every feature.
    full: (u64, u64),
    /// (flash, static RAM) of the build with only what the SSD1306 scene needs.
    minimal: (u64, u64),
    minimal_stack: u64,
}

/// Markdown rows: for each `(label, bench, elements)`, every board's
/// instructions per element.
fn table_rows(boards: &[&Report], rows: &[(&str, &str, u64)]) -> String {
    let mut md = String::new();
    for (label, key, n) in rows {
        md += &format!("| {label} |");
        for b in boards {
            md += &format!(
                " {:.1} |",
                b.benches[*key] as f64 * b.instr_per_tick / *n as f64
            );
        }
        md += "\n";
    }
    md
}

fn report(reports: &[BoardResult]) -> String {
    let tri_px = workloads::covered_pixels(&TRIANGLE_CMDS, workloads::SIDE).unwrap();
    let fill_px = workloads::covered_pixels(&FILL_CMDS, workloads::SIDE).unwrap();
    let eg_px = workloads::eg_covered_pixels(&TRIANGLE_CMDS);
    let mut md = String::from("# Instructions per pixel on emulated Cortex-M\n\n");
    md += "Generated by `cargo xtask report` (the firmware test with `TILERAST_REPORT`). \
           QEMU runs each firmware with `-icount shift=0`; SysTick counts the core clock, \
           so one tick is a fixed number of instructions (40 on `mps2-an386`, 62.5 on `microbit`). \
           Whole workloads and whole frames are timed, never single pixels; per-pixel figures \
           divide by the pixels the workload rasterizes (counted on the host: covered pixels \
           summed over commands, overdraw included). Two runs give identical counts (asserted).\n\n";
    md += &format!(
        "Workloads: one {s}x{s} tile; {t} small Gouraud triangles ({tri_px} pixels in \
         all, about 10 each, as a mesh on a small screen; setup included); {f} full-tile flat fills ({fill_px} pixels). \
         `embedded-graphics` fills the same triangles flat ({eg_px} pixels by its own rules).\n\n",
        s = workloads::SIDE, t = workloads::TRIANGLES, f = workloads::FILLS
    );
    let boards: Vec<&Report> = reports.iter().map(|r| &r.report).collect();
    md += "| workload | ";
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
        ("Gouraud + Z + window ID", "gouraud_z_wid_rgb565", tri_px),
        (
            "Gouraud + Z + window ID + 8x8 dither",
            "gouraud_z_wid_dither8_rgb565",
            tri_px,
        ),
        (
            "embedded-graphics `Triangle` fill (flat)",
            "eg_triangle_rgb565",
            eg_px,
        ),
    ];
    md += &table_rows(&boards, &rows);
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
           commands. *Flush*: the label and the flush, from the frame above. Millions of instructions.\n\n\
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
    for b in &boards {
        if let Some([frames, tiles, sent, full, bytes, ticks]) = b.anim {
            md += &format!(
                "\n## Partial updates ({})\n\nAn animated gauge (`targets/common/src/anim.rs`): 12 Gouraud \
                 wedges and a needle that turns every frame, 240x240 RGB565 + Z in 64x32 tiles, {frames} \
                 frames. Each finished tile is hashed (`Damage`) and sent only when it changed.\n\n\
                 | | tiles sent | bytes sent to the panel | per frame |\n| --- | ---: | ---: | ---: |\n\
                 | full refresh | {tiles} | {full} | {} |\n| partial updates | {sent} | {bytes} | {} |\n\n\
                 Bytes sent: **{:.1}%** of a full refresh. Rendering and hashing: {:.2} M instructions a frame.\n",
                b.board,
                full / frames,
                bytes / frames,
                100.0 * bytes as f64 / full as f64,
                ticks as f64 * b.instr_per_tick / frames as f64 / 1e6
            );
        }
    }
    md += "\n## Flash and RAM\n\nFlash is `.vector_table` + `.text` + `.rodata` (the scenes are in `.rodata`); \
           static RAM is `.data` + `.bss`; the stack high-water mark is measured by the firmware \
           (`cortex-m-rt`'s `paint-stack`). *Full*: both scenes and the workloads; *SSD1306 only*: \
           the features one 1-bit scene needs.\n\n| board | build | flash bytes | static RAM bytes | stack peak bytes |\n| --- | --- | ---: | ---: | ---: |\n";
    for r in reports {
        let b = &r.report;
        md += &format!(
            "| {} | full | {} | {} | {} |\n",
            b.board, r.full.0, r.full.1, b.stack_used
        );
        md += &format!(
            "| {} | SSD1306 only | {} | {} | {} |\n",
            b.board, r.minimal.0, r.minimal.1, r.minimal_stack
        );
    }
    md
}
