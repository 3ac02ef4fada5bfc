//! Building and running the QEMU firmware under `targets/`: shared by the
//! firmware test (`firmware.rs`) and the instruction profile
//! (`profile.rs`).

use std::path::{Path, PathBuf};
use std::process::Command as Process;
use tilerast_fw::report::{Demo, SceneKind, Ssd1306, Teapot, TeapotCull};
use tilerast_sim::Scene;
use tilerast_tests::{repo, scene};

/// Exports the demo scenes as firmware flash images; returns their folder.
pub fn export_scenes() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scenes");
    std::fs::create_dir_all(&dir).unwrap();
    for name in [Demo::NAME, Teapot::NAME, TeapotCull::NAME, Ssd1306::NAME] {
        let s = Scene::load(scene(&format!("{name}.toml"))).unwrap();
        std::fs::write(dir.join(format!("{name}.bin")), s.encode().unwrap()).unwrap();
    }
    // The teapot in model space, for the geometry stage on the device.
    let mesh = tilerast_sim::mesh::export_mesh(
        &repo().join("assets/models/teapot.obj"),
        &tilerast_sim::Limits::default(),
    )
    .unwrap();
    std::fs::write(dir.join("teapot.mesh"), mesh).unwrap();
    dir
}

fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

/// Builds a board's firmware with `features` (its default ones for
/// `None`), with the profiler's marks when `profile` (feature `profile`),
/// and returns the ELF path.
pub fn build_with(board: &str, scenes: &Path, features: Option<&str>, profile: bool) -> PathBuf {
    build_for(board, None, scenes, features, profile)
}

/// [`build_with`] for the target `triple` instead of the board's own
/// (`None`): Cortex-M0-class code on the MPS2 board.
pub fn build_for(
    board: &str,
    triple: Option<&str>,
    scenes: &Path,
    features: Option<&str>,
    profile: bool,
) -> PathBuf {
    build_in("release", board, triple, scenes, features, profile)
}

/// [`build_with`] in the boards' cargo profile `small` (`opt-level =
/// "s"`), without the profiler's marks: flash against instructions.
#[allow(dead_code)] // the profile test does not use it
pub fn build_small(board: &str, scenes: &Path, features: Option<&str>) -> PathBuf {
    build_in("small", board, None, scenes, features, false)
}

/// The builds above, in cargo profile `cargo_profile`.
fn build_in(
    cargo_profile: &str,
    board: &str,
    triple: Option<&str>,
    scenes: &Path,
    features: Option<&str>,
    profile: bool,
) -> PathBuf {
    let dir = repo().join("targets").join(board);
    let (_lock, fixed) = fixed_checkout();
    let manifest = fixed.join("targets").join(board).join("Cargo.toml");
    let mut cmd = Process::new(cargo());
    cmd.current_dir(&dir)
        .env("TILERAST_SCENES", scenes)
        .args(["build", "--profile", cargo_profile, "--quiet"])
        .arg("--manifest-path")
        .arg(&manifest);
    if let Some(t) = triple {
        cmd.args(["--target", t]);
    }
    let mut list: Vec<&str> = vec![];
    if let Some(f) = features {
        cmd.arg("--no-default-features");
        list.push(f);
    }
    if profile {
        list.push("profile");
    }
    if !list.is_empty() {
        cmd.args(["--features", &list.join(",")]);
    }
    let st = cmd.status().expect("cargo");
    assert!(st.success(), "building {board} firmware failed");
    let own = config_value(board, "target = ");
    let triple = triple.unwrap_or(&own);
    // Cargo puts the board's build where `CARGO_TARGET_DIR` says, if set
    // (relative to the board's directory, where cargo ran).
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(|t| dir.join(t))
        .unwrap_or_else(|| dir.join("target"));
    target
        .join(triple)
        .join(cargo_profile)
        .join(format!("tilerast-{board}"))
}

/// The checkout seen through one fixed path, and the lock that keeps it
/// there while a build runs.
///
/// Why: a board's firmware is its own Cargo workspace, and the core it
/// depends on (`../../core`) lies outside it. Cargo hashes such a path
/// dependency's *absolute* path into its symbol names (`-C metadata`), and
/// LTO's inlining follows the names: the same sources built in two
/// checkouts gave the M4's alpha-blended rectangle 5,096 and 5,557 ticks.
/// Built through one path, every checkout gives the same code, byte for
/// byte, so the reports' instruction counts do not depend on where the
/// repository was cloned. The path is a symbolic link in the temporary
/// folder, pointed at this checkout under an exclusive lock (held until the
/// returned file drops), so two checkouts building at once take turns.
pub fn fixed_checkout() -> (std::fs::File, PathBuf) {
    let tmp = std::env::temp_dir();
    let lock = std::fs::File::create(tmp.join("tilerast-src.lock")).expect("lock file");
    lock.lock().expect("locking tilerast-src.lock");
    let here = repo().canonicalize().expect("the checkout");
    #[cfg(unix)]
    {
        let link = tmp.join("tilerast-src");
        if std::fs::read_link(&link).ok().as_deref() != Some(here.as_path()) {
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(&here, &link).expect("linking the fixed path");
        }
        (lock, link)
    }
    // Elsewhere the checkout's own path: counts may then depend on it.
    #[cfg(not(unix))]
    (lock, here)
}

/// The first value of `key` (say `target = `) in a board's
/// `.cargo/config.toml`, unquoted: its target triple, its runner.
fn config_value(board: &str, key: &str) -> String {
    let path = repo()
        .join("targets")
        .join(board)
        .join(".cargo/config.toml");
    let config = std::fs::read_to_string(&path).unwrap();
    config
        .lines()
        .find_map(|l| l.strip_prefix(key))
        .unwrap_or_else(|| panic!("no `{key}` in {}", path.display()))
        .trim_matches('"')
        .to_string()
}

/// Runs a firmware ELF under QEMU with the runner its `.cargo/config.toml`
/// names, with more QEMU arguments (a `-plugin`, say) before `-kernel`;
/// returns what it printed.
pub fn run_with(board: &str, elf: &Path, extra: &[&str]) -> String {
    let runner = config_value(board, "runner = ");
    let mut words: Vec<&str> = runner.split_whitespace().collect();
    assert_eq!(words.pop(), Some("-kernel"), "{runner}");
    let out = Process::new(words[0])
        .args(&words[1..])
        .args(extra)
        .arg("-kernel")
        .arg(elf)
        .output()
        .unwrap_or_else(|e| panic!("{} (installed by `cargo xtask test`): {e}", words[0]));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{board} exited with {}:\n{text}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    text
}
