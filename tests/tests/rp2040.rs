//! The RP2040 board examples, end to end on an emulated RP2040: each
//! example's firmware (`targets/rp-pico-st7789`, `targets/rp-pico-ssd1306`,
//! built as a user builds it) runs unchanged on the rp2040js emulator with
//! the RP2040's boot ROM, its clocks, SPI, I2C and DMA, and an emulated
//! panel on its pins (`tests/rp2040/harness.js`). What reaches the panel is
//! checked byte for byte against the host's render of the same frames
//! (`tilerast_fw::examples`): the first differing pixel is named and both
//! images written. The firmware's `defmt` log is read from its RTT buffer in
//! RAM and decoded (`defmt-print`): no error may appear, and its own frames
//! per second line must. With `TILERAST_RP2040_REPORT` set, the figures go
//! to that file (`reports/rp2040.md`, by `cargo xtask report`).
//!
//! It needs Node, the harness's npm packages, the boot ROM and
//! `defmt-print`: `#[ignore]`d in a plain `cargo test`, run by
//! `cargo xtask test`, which installs them.

#[allow(dead_code)]
mod qemu;

use std::path::{Path, PathBuf};
use std::process::Command;
use tilerast::geometry::{Angle, Fx, Mesh, Scene, VertexSlot, CUBE_BYTES};
use tilerast::prelude::*;
use tilerast_fw::examples::{cube, oled};
use tilerast_tests::repo;

/// One frame as the harness measured it (`frames.jsonl`).
#[derive(Debug, Clone, Copy)]
struct Measured {
    cycles: u64,
    bytes: u64,
    bus_busy: u64,
    dma_wait: u64,
    clk_sys: u64,
}

/// The number after `"key":` in a line of the harness's JSON.
fn field(line: &str, key: &str) -> f64 {
    let at = line
        .find(&format!("\"{key}\":"))
        .unwrap_or_else(|| panic!("no {key} in {line}"));
    let rest = &line[at + key.len() + 3..];
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|_| panic!("{key} in {line}"))
}

/// What one run of an example on the emulated board left.
struct Run {
    example: &'static str,
    elf: PathBuf,
    dir: PathBuf,
    frames: Vec<Measured>,
    summary: String,
    log: Vec<String>,
}

impl Run {
    /// Frame `k`'s panel memory (`frame-NNN.raw`).
    fn raw(&self, k: usize) -> Vec<u8> {
        std::fs::read(self.dir.join(format!("frame-{k:03}.raw"))).unwrap()
    }
}

/// Builds `example` and runs it on the emulated board with its `panel`
/// until `frames` frames and `emulated_ms` of emulated time have passed.
fn run(example: &'static str, panel: &str, frames: u32, emulated_ms: u32) -> Run {
    let harness = repo().join("tests/rp2040");
    let rom = repo().join("target/rp2040/bootrom.py");
    assert!(
        harness.join("node_modules/rp2040js").exists() && rom.exists(),
        "the RP2040 harness is not installed (rp2040js, the boot ROM): run `cargo xtask test`"
    );
    let scenes = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let elf = qemu::build_with(example, &scenes, None, false);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("rp2040")
        .join(example);
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new("node")
        .arg(harness.join("harness.js"))
        .arg("--elf")
        .arg(&elf)
        .arg("--bootrom")
        .arg(&rom)
        .args(["--panel", panel, "--frames", &frames.to_string()])
        .args(["--min-emulated-ms", &emulated_ms.to_string()])
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap_or_else(|e| panic!("node (installed by `cargo xtask test`): {e}"));
    let summary = String::from_utf8_lossy(&out.stdout).trim().to_string();
    assert!(
        out.status.success(),
        "{example} on the emulated RP2040: {}\n{summary}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let frames = std::fs::read_to_string(dir.join("frames.jsonl"))
        .unwrap()
        .lines()
        .map(|l| Measured {
            cycles: field(l, "cycles") as u64,
            bytes: field(l, "bytes") as u64,
            bus_busy: field(l, "bus_busy_cycles") as u64,
            dma_wait: field(l, "dma_wait_cycles") as u64,
            clk_sys: field(l, "clk_sys") as u64,
        })
        .collect();
    let log = decode_log(&elf, &dir.join("defmt.bin"));
    Run {
        example,
        elf,
        dir,
        frames,
        summary,
        log,
    }
}

/// The firmware's `defmt` log, decoded by `defmt-print` with the ELF's
/// format strings: one line a message.
fn decode_log(elf: &Path, bytes: &Path) -> Vec<String> {
    let input = std::fs::File::open(bytes).unwrap();
    let out = Command::new("defmt-print")
        .arg("-e")
        .arg(elf)
        .stdin(input)
        .output()
        .unwrap_or_else(|e| panic!("defmt-print (installed by `cargo xtask test`): {e}"));
    assert!(
        out.status.success(),
        "defmt-print: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

/// The log has no error or panic, says the example is ready, and gives
/// its frames per second (returned).
fn check_log(r: &Run) -> u64 {
    let text = r.log.join("\n");
    assert!(
        !r.log.iter().any(|l| {
            let l = l.to_ascii_lowercase();
            l.contains("error") || l.contains("panic")
        }),
        "{}: the firmware logged an error:\n{text}",
        r.example
    );
    assert!(
        r.log.iter().any(|l| l.contains("ready")),
        "{}: no start-up line in the log:\n{text}",
        r.example
    );
    let fps = r
        .log
        .iter()
        .find_map(|l| {
            let head = l.split(" frames/s").next()?;
            (head.len() < l.len()).then(|| head.rsplit(' ').next()?.parse::<u64>().ok())?
        })
        .unwrap_or_else(|| panic!("{}: no frames/s line in the log:\n{text}", r.example));
    assert!(fps > 0, "{}: {fps} frames/s", r.example);
    fps
}

/// Compares the panel's memory after each frame with the host's; on a
/// difference names the first differing pixel and writes both images.
fn compare(
    r: &Run,
    host: &[Vec<u8>],
    w: usize,
    bytes_per_row: usize,
    pixel: impl Fn(usize, usize) -> (usize, u8),
) {
    assert!(
        !r.frames.is_empty(),
        "{}: no frame reached the panel",
        r.example
    );
    for (k, want) in host.iter().enumerate().take(r.frames.len()) {
        let got = r.raw(k);
        assert_eq!(got.len(), want.len(), "{} frame {k}: size", r.example);
        if &got == want {
            continue;
        }
        let at = (0..got.len()).find(|&i| got[i] != want[i]).unwrap();
        let (y, x) = (at / bytes_per_row, at % bytes_per_row);
        let (x, mask) = pixel(x, y);
        let host_file = r.dir.join(format!("frame-{k:03}.host.raw"));
        std::fs::write(&host_file, want).unwrap();
        panic!(
            "{} frame {k}: the panel differs from the host's render first at pixel ({x}, {y}) \
             (byte {at}, mask {mask:#04x}: panel {:#04x}, host {:#04x}); panel: {}, host: {} \
             (screen width {w})",
            r.example,
            got[at],
            want[at],
            r.dir.join(format!("frame-{k:03}.png")).display(),
            host_file.display(),
        );
    }
}

/// The host's ST7789 frames: the cube turned `k` steps, rendered in the
/// example's tiles and packed as the panel takes them (RGB565,
/// big-endian), into a 240x240 image.
fn cube_frames(n: usize) -> Vec<Vec<u8>> {
    let side = cube::SIDE as usize;
    let mut renderer = Box::new(cube::renderer().unwrap());
    let mut mesh_buf = [0u8; CUBE_BYTES];
    let mesh = Mesh::cube(&mut mesh_buf).unwrap();
    let mut slots = [VertexSlot::EMPTY; 24];
    let mut scene: Scene<'_, Fx> = Scene::new(&mut slots);
    cube::camera(&mut scene).unwrap();
    let mut angle = Angle::default();
    let mut out = vec![];
    for _ in 0..n {
        let mut img = vec![0u8; side * side * 2];
        cube::turn(&mut scene, &mesh, angle).unwrap();
        let mut buf = vec![0u8; cube::TILE_BYTES];
        renderer
            .render(&scene, |t| {
                let a = t.area();
                let n = t.panel_bytes(&mut buf).map_err(|_| ())?;
                let row = a.w as usize * 2;
                for (j, src) in buf[..n].chunks(row).enumerate() {
                    let at = ((a.y as usize + j) * side + a.x as usize) * 2;
                    img[at..at + row].copy_from_slice(src);
                }
                Ok::<(), ()>(())
            })
            .unwrap();
        out.push(img);
        angle = angle.add(cube::STEP);
    }
    out
}

/// The host's SSD1306 frames: the triangle turned `k` steps with its
/// label, as the SSD1306's memory holds them (8 pages of 128 column bytes,
/// bit `r` of a byte the page's row `r`).
fn oled_frames(n: usize) -> Vec<Vec<u8>> {
    let mut renderer = Box::new(oled::renderer().unwrap());
    let mut list: DisplayList<3> = DisplayList::new();
    let mut angle = 0.0f32;
    let mut out = vec![];
    for _ in 0..n {
        let mut ram = vec![0u8; 1024];
        oled::scene(&mut list, angle).unwrap();
        renderer
            .render(&list, |t| {
                let Ok(()) = oled::label(t);
                let a = t.area();
                for y in a.y..a.y + a.h as i32 {
                    for x in a.x..a.x + a.w as i32 {
                        if t.raw(x, y) == Some(1) {
                            ram[(y as usize / 8) * 128 + x as usize] |= 1 << (y % 8);
                        }
                    }
                }
                Ok::<(), ()>(())
            })
            .unwrap();
        out.push(ram);
        angle += oled::STEP;
    }
    out
}

/// The figures of one example's run, a row of `reports/rp2040.md`: the
/// first frame (boot and panel set-up) left out. With a `blocking` bus (no
/// DMA: the CPU drives each byte and waits for it) the wait is the bus's
/// whole busy time.
fn report_row(r: &Run, fps_logged: u64, bus: &str, blocking: bool) -> String {
    let steady: Vec<&Measured> = r.frames.iter().skip(1).collect();
    let n = steady.len().max(1) as u64;
    let mean = |f: &dyn Fn(&Measured) -> u64| steady.iter().map(|m| f(m)).sum::<u64>() / n;
    let (cycles, busy, bytes) = (
        mean(&|m| m.cycles),
        mean(&|m| m.bus_busy),
        mean(&|m| m.bytes),
    );
    let wait = if blocking {
        busy
    } else {
        mean(&|m| m.dma_wait)
    };
    let clk = r.frames[0].clk_sys;
    // The bus time the CPU spends rendering rather than waiting on it.
    let overlap = if busy > 0 {
        format!(
            "{:.0}%",
            100.0 * busy.saturating_sub(wait) as f64 / busy as f64
        )
    } else {
        "—".into()
    };
    format!(
        "| `{}` | {} | {:.0} MHz | {} | {} | {} | {} | {} | {} | {} | {:.1} | {} |",
        r.example,
        bus,
        clk as f64 / 1e6,
        steady.len(),
        cycles,
        cycles - wait,
        wait,
        busy,
        overlap,
        bytes,
        clk as f64 / cycles as f64,
        fps_logged
    )
}

#[test]
#[ignore = "needs Node, rp2040js, the RP2040 boot ROM and defmt-print: run `cargo xtask test`"]
fn rp2040_examples_run_end_to_end_and_the_panels_show_the_hosts_frames() {
    // A little over a second of emulated time: the examples log their
    // frames per second once a second.
    let st = run("rp-pico-st7789", "st7789", 8, 1500);
    let fps_st = check_log(&st);
    assert!(
        st.summary.contains("\"inverted\":true") && st.summary.contains("\"colmod\":85"),
        "the ST7789 was not set up as the example asks (INVON, COLMOD 0x55): {}",
        st.summary
    );
    let host = cube_frames(st.frames.len());
    compare(&st, &host, 240, 480, |x, _| (x / 2, 0xff));

    let ol = run("rp-pico-ssd1306", "ssd1306", 8, 1500);
    let fps_ol = check_log(&ol);
    assert!(
        ol.summary.contains("\"on\":true"),
        "the SSD1306 is not on: {}",
        ol.summary
    );
    let host = oled_frames(ol.frames.len());
    compare(&ol, &host, 128, 128, |x, _| (x, 0xff));

    for r in [&st, &ol] {
        eprintln!(
            "{}: {} frames equal the host's ({}); log:\n{}",
            r.example,
            r.frames.len(),
            r.elf.display(),
            r.log.join("\n")
        );
    }
    if let Some(path) = std::env::var_os("TILERAST_RP2040_REPORT") {
        let text = format!(
            "# The RP2040 examples on an emulated RP2040\n\n\
             Generated by `cargo xtask report` (`tests/tests/rp2040.rs` with \
             `TILERAST_RP2040_REPORT`). Each example's firmware, built as a user builds it, runs \
             unchanged on the rp2040js emulator (one Cortex-M0+ core, the RP2040 B1 boot ROM, \
             clocks and PLLs as the HAL sets them, PL022 SPI, I2C, DMA with DREQ pacing) with an \
             emulated panel on its pins (`tests/rp2040/harness.js`); the bus is timed as the \
             wire is (an SPI byte 8 clocks of the programmed rate, an I2C byte 9 SCL periods). \
             Every frame the panel received equals the host's render of the same frame, byte \
             for byte (asserted), and the firmware's own `defmt` log, read from its RTT buffer \
             in RAM, has no error. Cycles are the emulated core's (rp2040js's cycle counts), \
             means over the frames after the first (the first includes boot and the panel's \
             set-up). *Wait*: cycles the CPU polls a busy DMA channel (the ST7789 example's wait \
             for the tile before), or, on the SSD1306's blocking I2C, the bus's whole busy \
             time; *render*: the rest; *bus busy*: cycles the bus is shifting \
             bytes; *overlap*: the share of the bus time the CPU spends rendering instead of \
             waiting; *fps*: the clock over the cycles a frame; *logged*: the frames per \
             second line the firmware printed.\n\n\
             | example | bus | clk_sys | frames | cycles a frame | render | wait | bus busy | \
             overlap | bytes a frame | fps | logged fps |\n\
             | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n\
             {}\n{}\n\n\
             Both examples send every pixel every frame: the ST7789 example each 60x40 tile \
             (4,800 bytes) behind its CASET/RASET/RAMWR window (11 bytes), the SSD1306 driver \
             its whole buffer (1,024 bytes) and its address commands. Partial updates \
             (`Renderer::with_partial_updates`) would send only the tiles that changed; these \
             examples do not use them. The clock is what the HAL's `init_clocks_and_plls` \
             sets on a Pico, 125 MHz (the RP2040 is rated to 133 MHz: figures scale with \
             it). The emulated board found one bug on the way: the ST7789 examples flipped DC \
             for the next tile's window while the last bytes of the tile before were still in \
             the SPI FIFO (a DMA transfer is done once its bytes are in the FIFO), so the \
             panel took up to 8 pixel bytes a tile as commands; `tilerast_fw::panel::command` \
             now flushes the bus first.\n",
            report_row(&st, fps_st, "SPI 62.5 MHz, DMA ping-pong", false),
            report_row(&ol, fps_ol, "I2C 400 kHz, blocking", true),
        );
        std::fs::write(&path, text).unwrap();
    }
}
