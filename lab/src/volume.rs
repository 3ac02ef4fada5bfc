//! Volume rendering with normal blending against per-slice shading
//! (`tilerast-lab volume-report`, seed 002 §4.2, §5 Table 2, Figs. 2, 3
//! and 5).
//!
//! **Datasets**: the seed's procedural "small sphere" (64^3, generated in
//! code) and the real MRI head (`assets/volumes/`), resampled to 64^3,
//! 128^3 and 256^3 for the seed's size series. Slices: as many as the
//! volume's side (the seed: 64 for the sphere, 128 and 256 for the larger).
//! Viewports 256 x 256 and 512 x 512, RGB888, no dither, tiles 128 x 32.
//!
//! **Phases** (host time, median of timed renders): phase I slices,
//! classifies and composites; phase II shades. The baseline
//! (Meissner's per-slice shading) runs the same slicing and sampling code
//! and shades every composited sample instead of once per pixel.
//!
//! **Equality**: with one colour for every density (the seed's case,
//! intensity only), both images against each other: largest difference
//! and eq. 8 per pixel, and the rounding bound
//! ([`tilerast_sim::volume::equality_bound`]) for the worst pixel (every
//! slice blended). With colours from the table, the same comparison
//! measures the approximation normal blending makes.

use crate::chart::{err, grid, legend, line_with_dots, plot, SANS};
use plotters::prelude::*;
use std::path::Path;
use tilerast::prelude::*;
use tilerast_sim::metrics::compare;
use tilerast_sim::render::{Config, FormatKind};
use tilerast_sim::volume::{
    equality_bound, render, render_lights, ModeKind, NormalsKind, ViewKind, VolumeData, VolumeRun,
    VolumeScene, VolumeSpec,
};
use tilerast_sim::Image;

/// The MRI head vendored in the repository.
pub const MRI: &str = "assets/volumes/mni_icbm152_t1_09a_128.nii.gz";

/// The four-light set of the lighting comparison (towards each light, kd).
pub const FOUR_LIGHTS: [[f64; 4]; 4] = [
    [0.4, 0.6, 1.0, 0.5],
    [-0.7, 0.2, 0.6, 0.3],
    [0.0, -0.8, 0.5, 0.2],
    [0.8, -0.1, -0.3, 0.2],
];

/// One dataset at one viewport.
#[derive(Debug, Clone)]
pub struct Row {
    /// Dataset name.
    pub name: String,
    /// Volume side.
    pub side: u16,
    /// Viewport side.
    pub viewport: u16,
    /// Slices.
    pub slices: u16,
    /// Normal blending: set-up, phase I, phase II, ms.
    pub setup_ms: f64,
    /// Phase I, ms (skipping transparent bricks, the default).
    pub phase1_ms: f64,
    /// Phase I fetching every sample, ms.
    pub phase1_all_ms: f64,
    /// Phase II, ms.
    pub phase2_ms: f64,
    /// Per-slice shading, whole frame, ms.
    pub per_slice_ms: f64,
    /// Normals on the fly instead of precomputed, whole frame, ms.
    pub on_the_fly_ms: f64,
    /// Four lights: normal blending and per-slice shading, whole frame, ms.
    pub four_lights_ms: (f64, f64),
    /// Samples taken and blended (normal blending).
    pub samples: u64,
    /// Blended samples.
    pub composited: u64,
    /// Samples in transparent bricks, skipped without a fetch.
    pub skipped: u64,
    /// One colour: largest difference, eq. 8 per pixel, the bound.
    pub mono: (u8, f64, f64),
    /// Colours from the table: largest difference, eq. 8 per pixel.
    pub color: (u8, f64),
}

/// The report's render configuration at a `side` x `side` viewport:
/// RGB888, no dither, depth, tiles of up to 128 x 32.
pub fn config(side: u16) -> Config {
    Config {
        width: side,
        height: side,
        format: FormatKind::Rgb888,
        tile: (side.min(128), 32),
        dither: 0,
        depth: true,
        wid: false,
        clear: Clear::default(),
        aa: tilerast_sim::AaKind::None,
        cull: tilerast::command::Cull::None,
    }
}

/// The transfer functions: the sphere's shell, the MRI's cortex and its
/// white matter (the template is skull-stripped: Fig. 5's skin and bone
/// become the brain's outer surface and the white matter), each in one
/// colour or from a colour ramp.
pub fn transfer(name: &str, mono: bool) -> Vec<[f64; 5]> {
    let pts: Vec<[f64; 5]> = match name {
        "sphere" => vec![
            [100.0, 0.0, 255.0, 120.0, 60.0],
            [170.0, 60.0, 250.0, 230.0, 120.0],
            [230.0, 200.0, 255.0, 255.0, 255.0],
        ],
        "white matter" => vec![
            [190.0, 0.0, 200.0, 200.0, 255.0],
            [215.0, 200.0, 255.0, 240.0, 220.0],
        ],
        _ => vec![
            [35.0, 0.0, 255.0, 150.0, 120.0],
            [80.0, 160.0, 255.0, 225.0, 200.0],
            [160.0, 230.0, 255.0, 255.0, 255.0],
        ],
    };
    if mono {
        pts.iter()
            .map(|p| [p[0], p[1], 255.0, 230.0, 200.0])
            .collect()
    } else {
        pts
    }
}

/// A scene of `data` seen from the front, slightly turned.
pub fn scene(data: VolumeData, tf: &str, mono: bool, slices: u16) -> Result<VolumeScene, String> {
    let mri = tf != "sphere";
    let spec = VolumeSpec {
        slices,
        eye: [0.0, 0.0, 2.0],
        // The NIfTI axes: x left-right, y back-front, z up.
        rotate: if mri {
            [-90.0, 200.0, 0.0]
        } else {
            [0.0, 0.0, 0.0]
        },
        ..VolumeSpec::new(transfer(tf, mono))
    };
    let transfer = tilerast_sim::volume::transfer(&spec.transfer)?;
    VolumeScene::new(data, transfer, spec).map_err(|e| e.to_string())
}

/// One normal-blending render of `vs` (quantised normals, skipping
/// clear cells when `skip_empty`): the image and the phases' times.
pub fn run_normal(
    vs: &VolumeScene,
    cfg: &Config,
    skip_empty: bool,
) -> Result<(Image, tilerast_sim::volume::VolumeTiming), String> {
    run_once(
        vs,
        cfg,
        ModeKind::Normal,
        NormalsKind::Quantized,
        skip_empty,
    )
}

fn run_once(
    vs: &VolumeScene,
    cfg: &Config,
    mode: ModeKind,
    normals: NormalsKind,
    skip_empty: bool,
) -> Result<(Image, tilerast_sim::volume::VolumeTiming), String> {
    let run = VolumeRun {
        mode,
        normals,
        view: ViewKind::Shaded,
        slices: vs.spec.slices,
        skip_empty,
    };
    let (r, t) = render(cfg, &[], vs, run, &vs.spec.lights).map_err(|e| e.to_string())?;
    Ok((r.image, t))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Loads the datasets: the sphere and the MRI at each side.
pub fn datasets(root: &Path) -> Result<Vec<(String, VolumeData)>, String> {
    let mri = VolumeData::load_nifti(&root.join(MRI)).map_err(|e| e.to_string())?;
    let mut out = vec![(
        "sphere".to_string(),
        VolumeData::sphere(64).map_err(|e| e.to_string())?,
    )];
    for side in [64, 128, 256] {
        out.push((
            format!("MRI {side}^3"),
            mri.resample(side).map_err(|e| e.to_string())?,
        ));
    }
    Ok(out)
}

/// Measures every dataset at both viewports, `runs` timed renders each.
pub fn run(sets: &[(String, VolumeData)], runs: usize) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for (name, data) in sets {
        let side = data.dims[0];
        let tf = if name == "sphere" { "sphere" } else { "cortex" };
        let mono = scene(data.clone(), tf, true, side)?;
        let color = scene(data.clone(), tf, false, side)?;
        for vp in [256u16, 512] {
            let cfg = config(vp);
            let (mut p1, mut p2, mut su, mut ps, mut fly, mut p1all) =
                (vec![], vec![], vec![], vec![], vec![], vec![]);
            let (mut n4, mut ps4) = (vec![], vec![]);
            let mut four = color.clone();
            four.spec.lights = FOUR_LIGHTS.to_vec();
            let total =
                |t: &tilerast_sim::volume::VolumeTiming| t.setup_ns + t.phase1_ns + t.phase2_ns;
            let mut stats = Default::default();
            for _ in 0..runs {
                let (_, t) =
                    run_once(&color, &cfg, ModeKind::Normal, NormalsKind::Quantized, true)?;
                p1.push(t.phase1_ns);
                p2.push(t.phase2_ns);
                su.push(t.setup_ns);
                stats = t.stats;
                let (_, t) = run_once(
                    &color,
                    &cfg,
                    ModeKind::Normal,
                    NormalsKind::Quantized,
                    false,
                )?;
                p1all.push(t.phase1_ns);
                let (_, t) = run_once(
                    &color,
                    &cfg,
                    ModeKind::PerSlice,
                    NormalsKind::Quantized,
                    true,
                )?;
                ps.push(t.setup_ns + t.phase1_ns + t.phase2_ns);
                let (_, t) = run_once(&color, &cfg, ModeKind::Normal, NormalsKind::OnTheFly, true)?;
                fly.push(total(&t));
                let (_, t) = run_once(&four, &cfg, ModeKind::Normal, NormalsKind::Quantized, true)?;
                n4.push(total(&t));
                let (_, t) = run_once(
                    &four,
                    &cfg,
                    ModeKind::PerSlice,
                    NormalsKind::Quantized,
                    true,
                )?;
                ps4.push(total(&t));
            }
            let eq = |vs: &VolumeScene| -> Result<(u8, f64), String> {
                let (a, _) = run_once(vs, &cfg, ModeKind::Normal, NormalsKind::Quantized, true)?;
                let (b, _) = run_once(vs, &cfg, ModeKind::PerSlice, NormalsKind::Quantized, true)?;
                let d = compare(&a, &b).map_err(|e| e.to_string())?;
                Ok((d.max_abs, d.mse_per_pixel))
            };
            let m = eq(&mono)?;
            let bound = equality_bound(&mono.spec.lights, mono.spec.ambient, side as u32);
            rows.push(Row {
                name: name.clone(),
                side,
                viewport: vp,
                slices: side,
                setup_ms: median(su) / 1e6,
                phase1_ms: median(p1) / 1e6,
                phase1_all_ms: median(p1all) / 1e6,
                phase2_ms: median(p2) / 1e6,
                per_slice_ms: median(ps) / 1e6,
                on_the_fly_ms: median(fly) / 1e6,
                four_lights_ms: (median(n4) / 1e6, median(ps4) / 1e6),
                samples: stats.samples as u64,
                composited: stats.composited as u64,
                skipped: stats.skipped as u64,
                mono: (m.0, m.1, bound),
                color: eq(&color)?,
            });
            eprintln!("volume-report: {name} at {vp}x{vp} done");
        }
    }
    Ok(rows)
}

/// One brick side of the empty-space skipping sweep.
#[derive(Debug, Clone)]
pub struct BrickRow {
    /// Dataset name.
    pub name: String,
    /// Brick side as a shift; `None`: no skipping, or the cells' bits
    /// (`cells`).
    pub shift: Option<u32>,
    /// Skipping by the cells' bits, made for the transfer function.
    pub cells: bool,
    /// Bytes of brick ranges or cell bits.
    pub bytes: usize,
    /// Samples walked (the cell bits' box leaves the others out).
    pub samples: u64,
    /// Samples skipped without a fetch.
    pub skipped: u64,
    /// The frame's samples (those walked without skipping).
    pub frame: u64,
    /// Phase I, ms (median).
    pub phase1_ms: f64,
    /// Whether the image equals the one without skipping, every byte.
    pub exact: bool,
}

/// The brick-side knob: phase I and the samples skipped against the bytes
/// of brick ranges, for the sphere (64^3) and the MRI (128^3) at 256^2,
/// every image compared with the one that skips nothing.
pub fn bricks(sets: &[(String, VolumeData)], runs: usize) -> Result<Vec<BrickRow>, String> {
    let cfg = config(256);
    let mut rows = Vec::new();
    for (name, tf) in [("sphere", "sphere"), ("MRI 128^3", "cortex")] {
        let data = &sets.iter().find(|s| s.0 == name).ok_or("no dataset")?.1;
        let side = data.dims[0];
        let plain = scene(data.clone(), tf, false, side)?;
        let (want, _) = run_once(
            &plain,
            &cfg,
            ModeKind::Normal,
            NormalsKind::Quantized,
            false,
        )?;
        // No skipping, each brick side (by ranges), then the cells' bits.
        let sweep = std::iter::once((None, false))
            .chain(tilerast::volume::BRICK_SHIFTS.map(|k| (Some(k), false)))
            .chain([(None, true)]);
        let mut frame = 0;
        for (shift, cells) in sweep {
            let mut vs = match shift {
                Some(k) => scene(
                    data.clone()
                        .with_brick_shift(k)
                        .map_err(|e| e.to_string())?,
                    tf,
                    false,
                    side,
                )?,
                None => plain.clone(),
            };
            if !cells {
                vs.cells.clear();
            }
            let skip = shift.is_some() || cells;
            let mut p1 = vec![];
            let mut last = None;
            for _ in 0..runs {
                let (img, t) = run_once(&vs, &cfg, ModeKind::Normal, NormalsKind::Quantized, skip)?;
                p1.push(t.phase1_ns);
                last = Some((img, t.stats));
            }
            let (img, stats) = last.ok_or("no run")?;
            if !skip {
                frame = stats.samples as u64;
            }
            let bytes = match shift {
                Some(k) => tilerast::volume::brick_bytes(data.dims, k),
                None if cells => vs.cells.len(),
                None => 0,
            };
            rows.push(BrickRow {
                name: name.to_string(),
                shift,
                cells,
                bytes,
                samples: stats.samples as u64,
                skipped: stats.skipped as u64,
                frame,
                phase1_ms: median(p1) / 1e6,
                exact: img.pixels == want.pixels,
            });
        }
    }
    Ok(rows)
}

/// Phase I against the bytes of brick ranges, one line per dataset (the
/// point at 0 bytes: no skipping).
pub fn brick_chart(rows: &[BrickRow]) -> Result<Image, String> {
    plot(700, 380, |area| {
        let top = rows.iter().map(|r| r.phase1_ms).fold(1.0, f64::max) * 1.15;
        let most = rows.iter().map(|r| r.bytes).max().unwrap_or(1) as f64;
        let x = |b: usize| ((b as f64) + 64.0).log2();
        let mut c = ChartBuilder::on(area)
            .caption(
                "Empty-space skipping: phase I ms against bytes (256^2; x: cell bits)",
                (SANS, 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x(0) - 0.3..x(most as usize) + 0.5, 0.0..top)
            .map_err(err)?;
        c.configure_mesh()
            .x_desc("brick bytes (log; leftmost: no skipping)")
            .x_label_formatter(&|v| format!("{:.0}", (2f64.powf(*v) - 64.0).max(0.0)))
            .y_desc("phase I ms")
            .draw()
            .map_err(err)?;
        for (name, color) in [
            ("sphere", RGBColor(200, 60, 40)),
            ("MRI 128^3", RGBColor(30, 90, 200)),
        ] {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.name == name && !r.cells)
                .map(|r| (x(r.bytes), r.phase1_ms))
                .collect();
            line_with_dots(&mut c, pts, name, color)?;
            // The cells' bits: one point, a cross.
            for r in rows.iter().filter(|r| r.name == name && r.cells) {
                c.draw_series(std::iter::once(Cross::new(
                    (x(r.bytes), r.phase1_ms),
                    7,
                    color.stroke_width(2),
                )))
                .map_err(err)?;
            }
        }
        legend(&mut c, SeriesLabelPosition::UpperRight)
    })
}

/// A charted figure: name, value, colours at 256^2 and 512^2.
type Metric = (&'static str, fn(&Row) -> f64, [RGBColor; 2]);

/// Phase I and II (normal blending) and the per-slice baseline against the
/// dataset, per viewport (log scale).
pub fn chart(rows: &[Row]) -> Result<Image, String> {
    plot(900, 420, |area| {
        let n = rows.len() / 2;
        let top = rows
            .iter()
            .map(|r| r.per_slice_ms.max(r.phase1_ms))
            .fold(1.0, f64::max)
            * 2.0;
        let bottom = rows
            .iter()
            .map(|r| r.phase2_ms)
            .fold(f64::MAX, f64::min)
            .max(1e-3)
            / 2.0;
        let mut c = ChartBuilder::on(area)
            .caption("Volume rendering: host ms per frame (log)", (SANS, 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5f64..n as f64 - 0.5, (bottom..top).log_scale())
            .map_err(err)?;
        let names: Vec<String> = rows.iter().step_by(2).map(|r| r.name.clone()).collect();
        c.configure_mesh()
            .x_labels(n)
            .x_label_formatter(&|x| names.get(x.round() as usize).cloned().unwrap_or_default())
            .y_desc("ms")
            .draw()
            .map_err(err)?;
        let metrics: [Metric; 3] = [
            (
                "phase I",
                |r| r.phase1_ms,
                [RGBColor(30, 90, 200), RGBColor(120, 160, 240)],
            ),
            (
                "phase II",
                |r| r.phase2_ms,
                [RGBColor(200, 60, 40), RGBColor(240, 150, 120)],
            ),
            (
                "per-slice",
                |r| r.per_slice_ms,
                [RGBColor(40, 140, 60), RGBColor(130, 200, 140)],
            ),
        ];
        let series = metrics.iter().flat_map(|&(name, f, colors)| {
            [256u16, 512]
                .into_iter()
                .zip(colors)
                .map(move |(vp, color)| (format!("{name}, {vp}^2"), color, f, vp))
        });
        for (label, color, f, vp) in series {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.viewport == vp)
                .enumerate()
                .map(|(i, r)| (i as f64, f(r).max(bottom)))
                .collect();
            line_with_dots(&mut c, pts, label, color)?;
        }
        legend(&mut c, SeriesLabelPosition::UpperLeft)
    })
}

/// The figures, 256 x 256 each: row 1 the sphere's composited normals
/// (Fig. 2a), shaded (Fig. 2b), per-slice; row 2 the MRI lit from two
/// directions from one composite (Fig. 3) and per-slice; row 3 the two
/// transfer functions (Fig. 5), normals on the fly.
pub fn pictures(sets: &[(String, VolumeData)]) -> Result<Image, String> {
    let cfg = config(256);
    let e = |e: tilerast_sim::Error| e.to_string();
    let sphere = scene(sets[0].1.clone(), "sphere", false, 64)?;
    let mri = &sets
        .iter()
        .find(|s| s.0 == "MRI 128^3")
        .ok_or("no MRI 128^3")?
        .1;
    let cortex = scene(mri.clone(), "cortex", false, 128)?;
    let white = scene(mri.clone(), "white matter", false, 128)?;
    let shaded = |vs: &VolumeScene, mode, view, normals| -> Result<Image, String> {
        let run = VolumeRun {
            mode,
            normals,
            view,
            slices: vs.spec.slices,
            skip_empty: true,
        };
        Ok(render(&cfg, &[], vs, run, &vs.spec.lights)
            .map_err(e)?
            .0
            .image)
    };
    let q = NormalsKind::Quantized;
    let row1 = [
        shaded(&sphere, ModeKind::Normal, ViewKind::Normals, q)?,
        shaded(&sphere, ModeKind::Normal, ViewKind::Shaded, q)?,
        shaded(&sphere, ModeKind::PerSlice, ViewKind::Shaded, q)?,
    ];
    let two = render_lights(
        &cfg,
        &cortex,
        &[vec![[-0.8, 0.3, 0.6, 0.8]], vec![[0.8, 0.3, 0.6, 0.8]]],
    )
    .map_err(e)?;
    let row2 = [
        two[0].clone(),
        two[1].clone(),
        shaded(&cortex, ModeKind::PerSlice, ViewKind::Shaded, q)?,
    ];
    let row3 = [
        shaded(&cortex, ModeKind::Normal, ViewKind::Shaded, q)?,
        shaded(&white, ModeKind::Normal, ViewKind::Shaded, q)?,
        shaded(
            &white,
            ModeKind::Normal,
            ViewKind::Shaded,
            NormalsKind::OnTheFly,
        )?,
    ];
    Ok(grid(&[&row1, &row2, &row3]))
}

/// The Markdown report.
pub fn report(
    rows: &[Row],
    bricks: &[BrickRow],
    runs: usize,
    [chart, brick_chart, image]: [&Path; 3],
) -> String {
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let mut md = format!(
        "# Volume rendering with normal blending (seed 002)\n\n\
         Generated by `tilerast-lab volume-report` (`cargo xtask report`). Host time on this machine, \
         median of {runs} renders; RGB888, no dither, tiles 128 x 32 (the normal plane: 14 bytes a pixel, \
         56 KB a tile). Slices = the volume's side. Datasets: the seed's procedural sphere (64^3) and the \
         real MRI head (`{MRI}`, resampled trilinearly). Instructions on the emulated Cortex-M4 for a 32^3 \
         sphere are in `reports/targets.md`.\n\n\
         ## Table 2 analogue\n\n\
         Both methods skip the samples of cells the transfer function makes transparent (one bit a \
         voxel, made for the table: empty-space skipping, the same image, see below) and walk none \
         outside the box of the visible cells (*samples*: walked); *phase I, all* \
         fetches every sample.\n\n\
         | dataset | viewport | slices | samples | skipped | blended | set-up ms | phase I ms | phase I, all ms | phase II ms | total ms | per-slice ms | speed-up | on-the-fly normals ms |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for r in rows {
        let total = r.setup_ms + r.phase1_ms + r.phase2_ms;
        md += &format!(
            "| {} | {}^2 | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2}x | {:.2} |\n",
            r.name, r.viewport, r.slices, r.samples, r.skipped, r.composited, r.setup_ms, r.phase1_ms,
            r.phase1_all_ms, r.phase2_ms, total, r.per_slice_ms, r.per_slice_ms / total, r.on_the_fly_ms
        );
    }
    md += &format!(
        "\n## Empty-space skipping: the brick side, and cell bits\n\n\
         Each brick keeps the density range of the voxels its samples read (two bytes); a sample in a \
         brick whose whole range has zero opacity is skipped before its fetch. Trilinear interpolation \
         stays inside its corners' range, so the image is the same, every byte (*exact*). Smaller \
         bricks skip more and cost more bytes. *Cell bits* classify each cell through the transfer \
         function once (`Volume::compute_visible_cells`, one bit a voxel, made again when the table \
         changes; the ranges are not): the finest test, read from a sample's integer coordinates \
         alone; they end with the box of the visible cells, and the samples outside it are not even \
         walked. *Samples*: walked; *skipped %*: of the frame's samples (the first row's), skipped \
         or not walked. Normal blending at 256^2, median of {runs}.\n\n\
         | dataset | brick side | bytes | samples | skipped | skipped % | phase I ms | exact |\n\
         |---|---|---|---|---|---|---|---|\n"
    );
    for b in bricks {
        md += &format!(
            "| {} | {} | {} | {} | {} | {:.1}% | {:.2} | {} |\n",
            b.name,
            match (b.shift, b.cells) {
                (Some(k), _) => format!("{} cells", 1 << k),
                (None, true) => "cell bits".to_string(),
                (None, false) => "no skipping".to_string(),
            },
            b.bytes,
            b.samples,
            b.skipped,
            100.0 * (b.skipped + b.frame.saturating_sub(b.samples)) as f64 / b.frame.max(1) as f64,
            b.phase1_ms,
            if b.exact { "yes" } else { "**no**" }
        );
    }
    md += &format!("\n![bricks]({})\n", name(brick_chart));
    md += "\n## Lights, and lighting again\n\n\
         Per-slice shading pays for every light at every blended sample; normal blending pays once a \
         pixel. And new lights (a moving light, Fig. 3) re-run only phase II on the same composite, where \
         per-slice shading must composite the whole volume again.\n\n\
         | dataset | viewport | 4 lights: normal blending ms | per-slice ms | speed-up | new lights: phase II ms | per-slice ms | speed-up |\n\
         |---|---|---|---|---|---|---|---|\n";
    for r in rows {
        md += &format!(
            "| {} | {}^2 | {:.2} | {:.2} | {:.2}x | {:.3} | {:.2} | {:.0}x |\n",
            r.name,
            r.viewport,
            r.four_lights_ms.0,
            r.four_lights_ms.1,
            r.four_lights_ms.1 / r.four_lights_ms.0,
            r.phase2_ms,
            r.per_slice_ms,
            r.per_slice_ms / r.phase2_ms
        );
    }
    md += &format!(
        "\n![phases]({})\n\n\
         ## Equality (§4.2)\n\n\
         Normal blending against per-slice shading on the same frames. *One colour*: every density the \
         same colour, the seed's case; the bound is what rounding allows after every slice blends at a \
         pixel (`tilerast_sim::volume::equality_bound`, derived in `tilerast::volume`), in 8-bit levels. \
         *Table colours*: colour varies with density, where normal blending shows the mean colour times \
         the mean intensity — an approximation, measured.\n\n\
         | dataset | viewport | one colour: max | eq. 8 per pixel | bound | table colours: max | eq. 8 per pixel |\n\
         |---|---|---|---|---|---|---|\n",
        name(chart)
    );
    for r in rows {
        md += &format!(
            "| {} | {}^2 | {} | {:.4} | {:.2} | {} | {:.3} |\n",
            r.name, r.viewport, r.mono.0, r.mono.1, r.mono.2, r.color.0, r.color.1
        );
    }
    md += &format!(
        "\n## Figures\n\n![figures]({})\n\n\
         Row 1: the sphere's composited normals as colour (Fig. 2a), shaded once (Fig. 2b), per-slice \
         shading. Row 2: the MRI (cortex) lit from the left and from the right **from one composite** \
         (Fig. 3; only phase II runs again), and per-slice. Row 3: two transfer functions (Fig. 5; the \
         template is skull-stripped, so cortex and white matter stand in for skin and bone), the last \
         with normals computed on the fly.\n",
        name(image)
    );
    md
}
