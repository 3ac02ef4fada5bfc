//! The QEMU boards' build script (each board's `build = "../common/board-build.rs"`):
//! puts the board's `memory.x` where the linker finds it and rebuilds when
//! the exported scenes change.
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    fs::copy("memory.x", out.join("memory.x")).expect("memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-env-changed=TILERAST_SCENES");
    if let Some(dir) = env::var_os("TILERAST_SCENES") {
        for f in ["demo.bin", "ssd1306.bin"] {
            println!(
                "cargo:rerun-if-changed={}",
                PathBuf::from(&dir).join(f).display()
            );
        }
    }
}
