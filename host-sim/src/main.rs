//! `tilerast-sim`: render scene files to PNG with the tilerast core, render
//! the f64 reference, and compare images.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use tilerast_sim::{metrics, reference, Image, Scene};

#[derive(Parser)]
#[command(
    name = "tilerast-sim",
    version,
    about = "Host simulator for the tilerast rasterizer"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// Largest scene, OBJ or MTL file read, in bytes.
    #[arg(long, global = true, default_value_t = tilerast_sim::Limits::default().max_bytes)]
    max_file_bytes: u64,
    /// Longest line read from those files, in bytes.
    #[arg(long, global = true, default_value_t = tilerast_sim::Limits::default().max_line)]
    max_line_bytes: usize,
}

/// Line antialiasing modes.
#[derive(Clone, Copy, clap::ValueEnum)]
enum LineAa {
    /// Bresenham.
    Off,
    /// Two-point (Wu).
    Wu,
}

/// Geometry back ends.
#[derive(Clone, Copy, clap::ValueEnum)]
enum Backend {
    /// Single-precision floats (Cortex-M4F, M7).
    F32,
    /// I16F16 fixed point (Cortex-M0).
    Fixed,
}

/// Shading of meshes between their vertices.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum ShadingArg {
    /// Lit at the vertices, interpolated linearly (the core).
    Gouraud,
    /// Lit at the vertices and edge midpoints, interpolated quadratically
    /// (the core: seed 001 §IV.2).
    FastPhong,
    /// The normal interpolated and normalised at every pixel (the f64
    /// reference renderer; no firmware path).
    Phong,
}

/// A switch.
#[derive(Clone, Copy, clap::ValueEnum)]
enum OnOff {
    /// Off.
    Off,
    /// On.
    On,
}

#[derive(Subcommand)]
enum Cmd {
    /// Render a scene tile by tile with the fixed-point core.
    Render {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output PNG.
        #[arg(short, long, default_value = "out.png")]
        output: PathBuf,
        /// Also write the f64 reference render here and print the difference.
        #[arg(long)]
        reference: Option<PathBuf>,
        /// Override every line's antialiasing: `wu` (two-point) or `off` (Bresenham).
        #[arg(long, value_enum)]
        line_aa: Option<LineAa>,
        /// Override edge antialiasing of solids (seed 003 eq. 8) for every
        /// triangle and mesh: `on` or `off`.
        #[arg(long, value_enum)]
        edge_aa: Option<OnOff>,
        /// Override the coverage antialiasing mode (seed 000): none, the RUF
        /// buffer with 4/8/16 samples, or supersampling.
        #[arg(long, value_enum)]
        aa: Option<tilerast_sim::AaKind>,
        /// Override every mesh's shading: `gouraud`, `fast-phong` (both
        /// drawn by the core) or `phong` (exact, drawn by the f64
        /// reference renderer).
        #[arg(long, value_enum)]
        shading: Option<ShadingArg>,
        /// Override the perspective mode of textured meshes (seed 001
        /// §IV.3): `affine`, `quadratic` (the RE's), `exact` (a division
        /// per pixel) or `none` (their shade, untextured).
        #[arg(long, value_enum)]
        texture: Option<tilerast_sim::TexKind>,
    },
    /// Render a scene with the f64 reference renderer.
    Reference {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Supersample the ideal scene with an N x N grid per pixel (box
        /// filter): lines as 1-pixel-wide rectangles, solids by exact area,
        /// no edge antialiasing commands. 1 renders the pipeline's own
        /// semantics (pixel centres, two-point lines, eq. 8 edges).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
        samples: u32,
        /// Output PNG.
        #[arg(short, long, default_value = "reference.png")]
        output: PathBuf,
    },
    /// Encode a scene for firmware flash (header + commands, `tilerast::wire`).
    Export {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Encode an OBJ as a model-space mesh for firmware flash
    /// (`tilerast::geometry::Mesh`), drawn from any angle by the on-device
    /// geometry stage.
    ExportMesh {
        /// OBJ file (its `.mtl` diffuse colours become the groups' materials).
        obj: PathBuf,
        /// Output file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Write the firmware's rotating-mesh animation (`tilerast_fw::spin`:
    /// 240x240 RGB565 + Z16, 64x32 tiles) as an animated PNG: what a board
    /// shows, frame for frame.
    Animate {
        /// An OBJ file, or a mesh written by `export-mesh`.
        mesh: PathBuf,
        /// Frames for one full turn.
        #[arg(long, default_value_t = 48)]
        frames: u32,
        /// Frames per second of the animated PNG.
        #[arg(long, default_value_t = 24)]
        fps: u16,
        /// Geometry back end: `f32` (FPU parts) or `fixed` (the M0's).
        #[arg(long, value_enum, default_value = "f32")]
        backend: Backend,
        /// Output (animated PNG).
        #[arg(short, long, default_value = "spin.png")]
        output: PathBuf,
    },
    /// Compare two PNGs: seed 000 eq. 8 colour error, PSNR, max abs error.
    Compare {
        /// Test image.
        a: PathBuf,
        /// Reference image.
        b: PathBuf,
    },
}

fn run(cli: Cli) -> tilerast_sim::Result<()> {
    use tilerast_sim::Error;
    let limits = tilerast_sim::Limits {
        max_bytes: cli.max_file_bytes,
        max_line: cli.max_line_bytes,
    };
    let load = |p: &PathBuf| Scene::load_with(p, &limits);
    match cli.cmd {
        Cmd::Render {
            scene,
            output,
            reference: ref_out,
            line_aa,
            edge_aa,
            aa,
            shading,
            texture,
        } => {
            use tilerast_sim::mesh::ShadingKind;
            let kind = shading.map(|k| match k {
                ShadingArg::FastPhong => ShadingKind::FastPhong,
                ShadingArg::Gouraud | ShadingArg::Phong => ShadingKind::Gouraud,
            });
            let mut s = Scene::load_shaded(&scene, &limits, kind)?;
            if let Some(aa) = aa {
                if aa != tilerast_sim::AaKind::None && ![0, 4, 8].contains(&s.config.dither) {
                    return Err(Error::Unsupported(format!(
                        "--aa {}: the simulator builds coverage antialiasing with dither 0, 4 or 8, and this scene uses {}",
                        aa.name(),
                        s.config.dither
                    )));
                }
                s.config.aa = aa;
            }
            if let Some(mode) = line_aa {
                s.set_line_aa(matches!(mode, LineAa::Wu));
            }
            if let Some(mode) = edge_aa {
                s.set_edge_aa(matches!(mode, OnOff::On));
            }
            if let Some(mode) = texture {
                s.texturing = mode;
            }
            let c = &s.config;
            let r = s.render()?;
            println!("scene      {}", scene.display());
            for n in &s.notes {
                println!("           {n}");
            }
            println!(
                "screen     {}x{} {}, {} commands",
                c.width,
                c.height,
                c.format.name(),
                s.commands.len()
            );
            let dither = if c.dither > 1 {
                format!("{0}x{0} ordered (address bits)", c.dither)
            } else {
                "none".into()
            };
            println!(
                "pipeline   tile {}x{}, dither {dither}, Z plane {}, window-ID plane {}, coverage AA {}",
                c.tile.0,
                c.tile.1,
                if c.depth { "16-bit" } else { "none" },
                if c.wid { "8-bit" } else { "none" },
                c.aa.name()
            );
            println!("RAM        {} bits/pixel -> {} bytes per tile (a full frame buffer would be {} bytes)",
                r.bits_per_pixel, r.tile_bytes(c), (c.width as u64 * c.height as u64 * r.bits_per_pixel as u64).div_ceil(8));
            println!(
                "binning    {} tiles, {} command replays",
                r.stats.tiles, r.stats.replayed
            );
            let quads = s
                .commands
                .iter()
                .filter(|c| matches!(c, tilerast::command::Command::Quadratic { .. }))
                .count();
            if shading == Some(ShadingArg::Phong) {
                println!(
                    "shading    exact Phong on {} triangles: the f64 reference renderer (per-pixel normals)",
                    s.phong.len()
                );
                s.exact_phong().to_image().save_png(&output)?;
            } else {
                if quads > 0 {
                    println!(
                        "shading    fast Phong on {quads} triangles (quadratic, seed 001 §IV.2)"
                    );
                }
                if !s.textures.is_empty() {
                    println!(
                        "texture    {} textures, perspective {} (seed 001 §IV.3)",
                        s.textures.len(),
                        s.texturing.name()
                    );
                }
                r.image.save_png(&output)?;
            }
            println!("wrote      {}", output.display());
            if let Some(path) = ref_out {
                let img = s.reference().to_image();
                img.save_png(&path)?;
                println!("wrote      {} (f64 reference)", path.display());
                println!("{}", metrics::compare(&r.image, &img)?);
            }
        }
        Cmd::Reference {
            scene,
            samples,
            output,
        } => {
            let s = load(&scene)?;
            let img = if samples > 1 {
                reference::supersample(&s.config, &s.commands, samples)
            } else {
                s.reference()
            };
            img.to_image().save_png(&output)?;
            println!("wrote {}", output.display());
        }
        Cmd::Export { scene, output } => {
            let s = load(&scene)?;
            let bytes = s.encode()?;
            std::fs::write(&output, &bytes).map_err(|e| Error::io(&output, e))?;
            println!(
                "wrote {} ({} commands, {} bytes)",
                output.display(),
                s.commands.len(),
                bytes.len()
            );
        }
        Cmd::ExportMesh { obj, output } => {
            let bytes = tilerast_sim::mesh::export_mesh(&obj, &limits)?;
            std::fs::write(&output, &bytes).map_err(|e| Error::io(&output, e))?;
            let m = tilerast::geometry::Mesh::parse(&bytes)?;
            println!(
                "wrote {} ({} vertices, {} triangles, {} groups, {} bytes)",
                output.display(),
                m.vertices(),
                m.triangles(),
                m.groups(),
                bytes.len()
            );
        }
        Cmd::Animate {
            mesh,
            frames,
            fps,
            backend,
            output,
        } => {
            let bytes = if mesh
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
            {
                tilerast_sim::mesh::export_mesh(&mesh, &limits)?
            } else {
                tilerast_sim::obj::read_bounded(&mesh, &limits)?
            };
            let stats = match backend {
                Backend::F32 => tilerast_sim::mesh::animate::<f32>(&bytes, frames, fps, &output)?,
                Backend::Fixed => tilerast_sim::mesh::animate::<tilerast::geometry::Fx>(
                    &bytes, frames, fps, &output,
                )?,
            };
            let front: u32 = stats.iter().map(|s| s.front).sum();
            println!(
                "wrote {} ({} frames of 240x240, {:.0} front-facing triangles per frame on average)",
                output.display(),
                stats.len(),
                front as f64 / stats.len().max(1) as f64
            );
        }
        Cmd::Compare { a, b } => {
            let d = metrics::compare(&Image::load_png(&a)?, &Image::load_png(&b)?)?;
            println!("{d}");
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
