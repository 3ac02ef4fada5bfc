//! `tilerast-sim`: render scene files to PNG with the tilerast core, render
//! the f64 reference, and compare images.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use tilerast_sim::{metrics, reference, render, Image, Scene};

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
    /// Measure every antialiasing mode against the 16x16 supersampled ideal
    /// (lines: Bresenham, Wu, embedded-graphics, tiny-skia; solids:
    /// aliased, edge AA, tiny-skia; and the scenes given, edge AA off and
    /// on). Writes a Markdown table and a side-by-side picture.
    AaReport {
        /// Scene files to measure with edge antialiasing off and on.
        scenes: Vec<PathBuf>,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/aa.md")]
        output: PathBuf,
        /// Picture: per row the ideal, then each mode, enlarged.
        #[arg(long, default_value = "reports/aa.png")]
        image: PathBuf,
    },
    /// Reproduce the RUF-buffer paper's Tables 1-4 on the OBJ models:
    /// Markdown tables, a chart of Table 2 and the renders side by side.
    RufReport {
        /// Folder of OBJ models (every `.obj` in it, by name).
        #[arg(long, default_value = "assets/models")]
        models: PathBuf,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/ruf.md")]
        output: PathBuf,
        /// Chart of Table 2.
        #[arg(long, default_value = "reports/ruf_chart.png")]
        chart: PathBuf,
        /// Renders: per model 1p, 8ss, RUF-8, 4x4 and the 8x8 reference.
        #[arg(long, default_value = "reports/ruf_models.png")]
        renders: PathBuf,
    },
    /// Sweep every knob (colour and Z fraction bits, depth bits, sub-pixel
    /// bits, dither per format, antialiasing of solids, line mode) on a
    /// fixed set of scenes and measure error and cost: Markdown, CSV and a
    /// chart with each Pareto front. Takes a few seconds (progress on
    /// stderr); run it from a release build.
    Tradeoff {
        /// Folder of the seeds' OBJ models (teapot, dolphins).
        #[arg(long, default_value = "assets/models")]
        models: PathBuf,
        /// Leave the model scenes out (quick look).
        #[arg(long)]
        no_models: bool,
        /// Timed renders per setting; the median is reported.
        #[arg(long, default_value_t = 15, value_parser = clap::value_parser!(u64).range(1..=100))]
        runs: u64,
        /// Samples per pixel side of the ideal.
        #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=64))]
        samples: u32,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/tradeoff.md")]
        output: PathBuf,
        /// CSV output.
        #[arg(long, default_value = "reports/tradeoff.csv")]
        csv: PathBuf,
        /// Chart output.
        #[arg(long, default_value = "reports/tradeoff.png")]
        chart: PathBuf,
    },
    /// Compare two PNGs: seed 000 eq. 8 colour error, PSNR, max abs error.
    Compare {
        /// Test image.
        a: PathBuf,
        /// Reference image.
        b: PathBuf,
    },
}

fn run(cli: Cli) -> Result<(), String> {
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
        } => {
            let mut s = load(&scene)?;
            if let Some(aa) = aa {
                if aa != tilerast_sim::AaKind::None && ![0, 4, 8].contains(&s.config.dither) {
                    return Err(format!(
                        "--aa {}: the simulator builds coverage antialiasing with dither 0, 4 or 8, and this scene uses {}",
                        aa.name(),
                        s.config.dither
                    ));
                }
                s.config.aa = aa;
            }
            if let Some(mode) = line_aa {
                s.set_line_aa(matches!(mode, LineAa::Wu));
            }
            if let Some(mode) = edge_aa {
                s.set_edge_aa(matches!(mode, OnOff::On));
            }
            let c = &s.config;
            let r = render(c, &s.commands).map_err(|e| e.to_string())?;
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
            r.image.save_png(&output)?;
            println!("wrote      {}", output.display());
            if let Some(path) = ref_out {
                let img = reference::render(c, &s.commands).to_image();
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
                reference::render(&s.config, &s.commands)
            };
            img.to_image().save_png(&output)?;
            println!("wrote {}", output.display());
        }
        Cmd::Export { scene, output } => {
            let s = load(&scene)?;
            let bytes = s.encode().map_err(|e| e.to_string())?;
            std::fs::write(&output, &bytes).map_err(|e| format!("{}: {e}", output.display()))?;
            println!(
                "wrote {} ({} commands, {} bytes)",
                output.display(),
                s.commands.len(),
                bytes.len()
            );
        }
        Cmd::AaReport {
            scenes,
            output,
            image,
        } => {
            let scenes = scenes.iter().map(load).collect::<Result<Vec<_>, _>>()?;
            let groups = tilerast_sim::aa::measure(&scenes);
            let table = tilerast_sim::aa::table(&groups);
            let md = format!(
                "# Antialiasing quality against the ideal\n\n\
                 Generated by `tilerast-sim aa-report` (`cargo xtask bench`). Every render is\n\
                 compared with the same geometry supersampled 16x16 per pixel (box filter;\n\
                 lines as 1-pixel-wide rectangles). RGB888, no dither. Error: seed 000 eq. 8\n\
                 (sum over R, G, B of squared differences), here per pixel; lower is better.\n\n{table}\n\
                 Picture: `{}` (per row: the ideal, then the modes in table order).\n",
                image.display()
            );
            for p in [&output, &image] {
                if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
                }
            }
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            tilerast_sim::aa::montage(&groups, 2).save_png(&image)?;
            print!("{table}");
            println!("wrote {} and {}", output.display(), image.display());
        }
        Cmd::RufReport {
            models,
            output,
            chart,
            renders,
        } => {
            let mut objs: Vec<PathBuf> = std::fs::read_dir(&models)
                .map_err(|e| format!("{}: {e}", models.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "obj"))
                .collect();
            objs.sort();
            let mut results = Vec::new();
            for obj in &objs {
                eprintln!("measuring {}", obj.display());
                results.push(tilerast_sim::ruf::measure(obj)?);
            }
            let md = tilerast_sim::ruf::markdown(&results)
                + &format!(
                    "\nChart: `{}`. Renders (per model: 1p, 8ss, RUF-8, 4x4, 8x8 reference): `{}`.\n",
                    chart.display(),
                    renders.display()
                );
            for p in [&output, &chart, &renders] {
                if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
                }
            }
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            tilerast_sim::ruf::chart(&results).save_png(&chart)?;
            let rows: Vec<(Image, Vec<tilerast_sim::aa::Measured>)> = results
                .iter()
                .map(|r| {
                    let mut imgs = r.images.clone();
                    let first = imgs.remove(0);
                    let rest = imgs
                        .into_iter()
                        .map(|image| tilerast_sim::aa::Measured {
                            subject: r.name.clone(),
                            mode: String::new(),
                            diff: tilerast_sim::metrics::compare(&image, &image).expect("same"),
                            image,
                        })
                        .collect();
                    (first, rest)
                })
                .collect();
            tilerast_sim::aa::montage(&rows, 1).save_png(&renders)?;
            print!("{md}");
        }
        Cmd::Tradeoff {
            models,
            no_models,
            runs,
            samples,
            output,
            csv,
            chart,
        } => {
            use tilerast_sim::tradeoff;
            let opt = tradeoff::Options {
                models: (!no_models).then_some(models),
                runs: runs as usize,
                ideal_samples: samples,
                progress: true,
            };
            let points = tradeoff::run(&opt)?;
            for p in [&output, &csv, &chart] {
                if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
                }
            }
            let md = tradeoff::report(&points, &opt, &chart, &csv);
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            std::fs::write(&csv, tradeoff::csv(&points))
                .map_err(|e| format!("{}: {e}", csv.display()))?;
            tradeoff::chart(&points).save_png(&chart)?;
            print!("{md}");
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
