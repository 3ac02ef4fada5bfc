//! `tilerast-lab`: the paper reproductions and sweeps, as reports with
//! tables and charts (`reports/`).

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use tilerast_sim::{Image, Scene};

#[derive(Parser)]
#[command(
    name = "tilerast-lab",
    version,
    about = "Measurements of the tilerast rasterizer: antialiasing quality, the RUF-buffer tables, the speed-against-accuracy sweep"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
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
    /// Time whole frames (core tiled and binned, one big tile, the f64
    /// reference) and filled triangles against embedded-graphics and
    /// tiny-skia, in one run. Writes a Markdown report.
    Frames {
        /// Scene files to time.
        scenes: Vec<PathBuf>,
        /// Timed renders per measurement; the median is reported.
        #[arg(long, default_value_t = 15)]
        runs: usize,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/frames.md")]
        output: PathBuf,
    },
    /// Fast Phong (ours, quadratic through vertex and edge-midpoint
    /// colours), Bishop-Weimer's Taylor variant and Gouraud against exact
    /// Phong on spheres of every tessellation and the teapot: error against
    /// the spread of normals, highlight offset, host cost.
    PhongReport {
        /// Folder of the seeds' OBJ models (the teapot).
        #[arg(long, default_value = "assets/models")]
        models: PathBuf,
        /// Timed renders per method; the median is reported.
        #[arg(long, default_value_t = 9)]
        runs: usize,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/phong.md")]
        output: PathBuf,
        /// Chart: largest error against the spread of normals.
        #[arg(long, default_value = "reports/phong_chart.png")]
        chart: PathBuf,
        /// Pictures: Gouraud, fast Phong, Taylor, exact Phong.
        #[arg(long, default_value = "reports/phong.png")]
        image: PathBuf,
    },
    /// Perspective texturing — affine, quadratic (the RE's), exact
    /// division — against the f64 mapping on a wall at depth ratios 1 to
    /// 16: texel error and host cost.
    TextureReport {
        /// Timed renders per mode; the median is reported.
        #[arg(long, default_value_t = 9)]
        runs: usize,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/texture.md")]
        output: PathBuf,
        /// Chart: largest texel error against the depth ratio.
        #[arg(long, default_value = "reports/texture_chart.png")]
        chart: PathBuf,
        /// Pictures: affine, quadratic, exact at depth ratio 6.
        #[arg(long, default_value = "reports/texture.png")]
        image: PathBuf,
    },
    /// Volume rendering with normal blending against per-slice shading
    /// (seed 002): the Table 2 analogue (phase I and II against volume and
    /// viewport size), the equality of §4.2 with its rounding bound, and
    /// the figures (normals, two lights from one composite, two transfer
    /// functions). Run from the repository root, in release.
    /// Occlusion culling (seed 004): the single pass against stop-and-wait
    /// and CHC occlusion queries and no culling, on the city walks (large
    /// and small triangles): ACPF, the Table 1 improvements, thresholds and
    /// block sizes. Run from the repository root, in release.
    CullReport {
        /// Frames of the camera path.
        #[arg(long, default_value_t = 200)]
        frames: u32,
        /// Walks of the path per row: each frame's time is its fastest.
        #[arg(long, default_value_t = 3)]
        runs: usize,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/cull.md")]
        output: PathBuf,
        /// Chart: ACPF per mode.
        #[arg(long, default_value = "reports/cull_chart.png")]
        chart: PathBuf,
        /// Frames of each variant.
        #[arg(long, default_value = "reports/cull.png")]
        image: PathBuf,
    },
    VolumeReport {
        /// Timed renders per measurement; the median is reported.
        #[arg(long, default_value_t = 3)]
        runs: usize,
        /// Markdown output.
        #[arg(short, long, default_value = "reports/volume.md")]
        output: PathBuf,
        /// Chart: phase I, phase II and the baseline per dataset.
        #[arg(long, default_value = "reports/volume_chart.png")]
        chart: PathBuf,
        /// Chart: phase I against the bytes of empty-space bricks.
        #[arg(long, default_value = "reports/volume_bricks.png")]
        bricks_chart: PathBuf,
        /// Figures.
        #[arg(long, default_value = "reports/volume.png")]
        image: PathBuf,
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
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.cmd {
        Cmd::Frames {
            scenes,
            runs,
            output,
        } => {
            let md = tilerast_lab::frames::report(&scenes, runs.max(1))?;
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            print!("{md}");
            println!("wrote {}", output.display());
        }
        Cmd::PhongReport {
            models,
            runs,
            output,
            chart,
            image,
        } => {
            use tilerast_lab::phong;
            let (rows, pics) = phong::run(&models, runs.max(1))?;
            phong::chart(&rows)?.save_png(&chart)?;
            // The coarsest specular sphere and the specular teapot.
            let pick: Vec<&[Image; 4]> = rows
                .iter()
                .zip(&pics)
                .filter(|(r, _)| r.specular && (r.scene == "sphere 8" || r.scene == "teapot"))
                .map(|(_, p)| p)
                .collect();
            if !pick.is_empty() {
                phong::pictures(&pick).save_png(&image)?;
            }
            let md = phong::report(&rows, &chart, &image);
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            print!("{md}");
        }
        Cmd::TextureReport {
            runs,
            output,
            chart,
            image,
        } => {
            use tilerast_lab::texture;
            let rows = texture::run(runs.max(1))?;
            texture::chart(&rows)?.save_png(&chart)?;
            texture::pictures()?.save_png(&image)?;
            let md = texture::report(&rows, &chart, &image);
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            print!("{md}");
        }
        Cmd::CullReport {
            frames,
            runs,
            output,
            chart,
            image,
        } => {
            use tilerast_lab::cull;
            let timing = cull::Timing { runs: runs.max(1) };
            let rows = cull::run(frames.max(2), timing)?;
            cull::chart(&rows)?.save_png(&chart)?;
            cull::pictures(frames.max(2))?.save_png(&image)?;
            let md = cull::report(&rows, timing, &chart, &image);
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            print!("{md}");
        }
        Cmd::VolumeReport {
            runs,
            output,
            chart,
            bricks_chart,
            image,
        } => {
            use tilerast_lab::volume;
            let sets = volume::datasets(std::path::Path::new("."))?;
            let rows = volume::run(&sets, runs.max(1))?;
            let bricks = volume::bricks(&sets, runs.max(1))?;
            volume::chart(&rows)?.save_png(&chart)?;
            volume::brick_chart(&bricks)?.save_png(&bricks_chart)?;
            volume::pictures(&sets)?.save_png(&image)?;
            let md = volume::report(&rows, &bricks, runs.max(1), [&chart, &bricks_chart, &image]);
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            print!("{md}");
        }
        Cmd::AaReport {
            scenes,
            output,
            image,
        } => {
            let scenes = scenes
                .iter()
                .map(Scene::load)
                .collect::<Result<Vec<_>, _>>()?;
            let groups = tilerast_lab::aa::measure(&scenes);
            let table = tilerast_lab::aa::table(&groups);
            let md = format!(
                "# Antialiasing quality against the ideal\n\n\
                 Generated by `tilerast-lab aa-report` (`cargo xtask bench`). Every render is\n\
                 compared with the same geometry supersampled 16x16 per pixel (box filter;\n\
                 lines as 1-pixel-wide rectangles). RGB888, no dither. Error: seed 000 eq. 8\n\
                 (sum over R, G, B of squared differences), here per pixel; lower is better.\n\
                 Cost of ours: host time of the pipeline (median of {} renders, ns per screen\n\
                 pixel; this shared VM varies, compare within the table) and the tile's RAM per\n\
                 pixel (area sampling adds no plane; RUF and supersampling add theirs). The\n\
                 chips' cost of each family: `reports/targets.md`.\n\n{table}\n\
                 Picture: `{}` (per row: the ideal, then the modes in table order).\n",
                tilerast_lab::aa::TIMED_RUNS,
                image.display()
            );
            for p in [&output, &image] {
                if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
                }
            }
            std::fs::write(&output, &md).map_err(|e| format!("{}: {e}", output.display()))?;
            tilerast_lab::aa::montage(&groups, 2).save_png(&image)?;
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
                results.push(tilerast_lab::ruf::measure(obj)?);
            }
            let md = tilerast_lab::ruf::markdown(&results)
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
            tilerast_lab::ruf::chart(&results)?.save_png(&chart)?;
            let rows: Vec<(Image, Vec<tilerast_lab::aa::Measured>)> = results
                .iter()
                .map(|r| {
                    let mut imgs = r.images.clone();
                    let first = imgs.remove(0);
                    let rest = imgs
                        .into_iter()
                        .map(|image| tilerast_lab::aa::Measured {
                            subject: r.name.clone(),
                            mode: String::new(),
                            diff: tilerast_sim::metrics::compare(&image, &image).expect("same"),
                            image,
                            cost: None,
                        })
                        .collect();
                    (first, rest)
                })
                .collect();
            tilerast_lab::aa::montage(&rows, 1).save_png(&renders)?;
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
            use tilerast_lab::tradeoff;
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
            tradeoff::chart(&points)?.save_png(&chart)?;
            print!("{md}");
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("tilerast-lab: {e}");
            ExitCode::FAILURE
        }
    }
}
