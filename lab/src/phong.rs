//! Fast Phong against exact Phong and Gouraud (`tilerast-lab phong-report`,
//! seed 001 §IV.2): the error of each way of shading between the vertices,
//! as a function of how far a triangle's normals spread, and its cost.
//!
//! **Methods**, all drawn by the core except the reference:
//! - *Gouraud*: lit at the vertices, interpolated linearly;
//! - *fast Phong* (ours, [`tilerast::geometry::Shading::FastPhong`]): lit
//!   at the vertices and the edge midpoints (normal `n_a + n_b`,
//!   normalised), the quadratic through the six colours stepped by
//!   forward differences ([`tilerast::command::Command::Quadratic`]);
//! - *Taylor* (Bishop & Weimer '86, the seed's citation): the Phong colour
//!   expanded to second order about the centroid
//!   ([`tilerast_sim::mesh::PhongTri::taylor`], in f64 on the host here),
//!   drawn by the same quadratic command — the same per-pixel cost, only
//!   the six colours differ;
//! - *exact Phong* (the reference): the normal interpolated with the
//!   triangle's screen-space weights and normalised at every pixel, lit in
//!   f64 ([`tilerast_sim::Scene::exact_phong`]'s shading).
//!
//! **Scenes**: a UV sphere tessellated from 6 to 48 slices (so the spread
//! of normals over a triangle runs from 60° down to under 8°), diffuse and
//! with a Blinn-Phong highlight, and the seed's teapot. 240x240 RGB888
//! without dither, so the numbers are the shading's, not the display's.
//!
//! **Error** per covered pixel against exact Phong (unrounded): the
//! largest channel error (LSB), seed 000 eq. 8 per pixel, the share of
//! pixels more than 2 LSB off, and for highlights the distance between the
//! centroids of the brightest pixels (within 2 of the maximum luminance).
//! **Cost**: host ns per covered pixel (median of timed renders); the
//! firmware's instructions per pixel are in `reports/targets.md`.

use crate::chart::{err, plot, SANS};
use plotters::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use tilerast::prelude::*;
use tilerast::tile::Clear;
use tilerast_sim::mesh::{self, MeshSpec, PhongTri, ShadingKind};
use tilerast_sim::reference::{self, RefFrame};
use tilerast_sim::render::{render_timed, AaKind, Config, FormatKind};
use tilerast_sim::Image;

/// Methods in table order.
pub const METHODS: [&str; 3] = ["Gouraud", "fast Phong (ours)", "Taylor (Bishop-Weimer)"];

/// Fast Phong's target: within this many LSB of exact Phong on diffuse.
pub const TARGET_LSB: f64 = 2.0;

/// One scene's measurements.
#[derive(Debug, Clone)]
pub struct Row {
    /// Scene name.
    pub scene: String,
    /// Whether the material has a highlight.
    pub specular: bool,
    /// Largest and mean spread of normals over a drawn triangle, degrees.
    pub spread: (f64, f64),
    /// Triangles drawn; of them quadratic slivers drawn Gouraud.
    pub triangles: usize,
    /// Slivers (drawn Gouraud-shaded by the quadratic methods).
    pub slivers: usize,
    /// Share of covered pixels in triangles that straddle the terminator
    /// (the kink of `max(0, N·L)`: some of the six points lit, some not)
    /// or that fast Phong draws Gouraud-shaded (creases).
    pub kinked: f64,
    /// Per method: largest error (LSB), eq. 8 per pixel, share over 2 LSB,
    /// highlight offset (px), host ns per covered pixel.
    pub methods: [Method; 3],
}

/// One method's figures on one scene.
#[derive(Debug, Clone, Copy, Default)]
pub struct Method {
    /// Largest channel error against exact Phong, LSB.
    pub max: f64,
    /// The same away from the terminator and creases ([`Row::kinked`]).
    pub smooth_max: f64,
    /// Seed 000 eq. 8 per covered pixel.
    pub eq8: f64,
    /// Share of covered pixels more than 2 LSB off.
    pub over2: f64,
    /// Distance between the highlight centroids, pixels (specular only).
    pub highlight: Option<f64>,
    /// Host time per covered pixel, ns.
    pub ns: f64,
}

/// A UV sphere of `slices` around and `slices / 2` stacks, unit radius,
/// with exact normals, and its material (`.obj`, `.mtl` text).
pub fn sphere(slices: u32) -> (String, String) {
    let stacks = (slices / 2).max(2);
    let mut obj = String::from("mtllib sphere.mtl\nusemtl paint\n");
    let mut idx = HashMap::new();
    let mut n = 0;
    let mut vert = |obj: &mut String, i: u32, j: u32| -> u32 {
        let key = if j == 0 || j == stacks {
            (0, j)
        } else {
            (i % slices, j)
        };
        *idx.entry(key).or_insert_with(|| {
            let (th, ph) = (
                key.0 as f64 * std::f64::consts::TAU / slices as f64,
                j as f64 * std::f64::consts::PI / stacks as f64,
            );
            let p = [ph.sin() * th.cos(), ph.cos(), ph.sin() * th.sin()];
            obj.push_str(&format!(
                "v {} {} {}\nvn {} {} {}\n",
                p[0], p[1], p[2], p[0], p[1], p[2]
            ));
            n += 1;
            n
        })
    };
    let mut faces = String::new();
    for j in 0..stacks {
        for i in 0..slices {
            let (a, b) = (vert(&mut obj, i, j), vert(&mut obj, i + 1, j));
            let (c, d) = (vert(&mut obj, i + 1, j + 1), vert(&mut obj, i, j + 1));
            // Counter-clockwise seen from outside.
            if j > 0 {
                faces.push_str(&format!("f {a}//{a} {b}//{b} {c}//{c}\n"));
            }
            if j + 1 < stacks {
                faces.push_str(&format!("f {a}//{a} {c}//{c} {d}//{d}\n"));
            }
        }
    }
    obj.push_str(&faces);
    let mtl = "newmtl paint\nKa 0.8 0.35 0.2\nKd 0.8 0.35 0.2\nKs 0.7 0.7 0.7\nNs 40\n";
    (obj, mtl.to_string())
}

/// The report's configuration: 240x240 RGB888 without dither, Z, 64x32
/// tiles.
pub fn config() -> Config {
    Config {
        width: 240,
        height: 240,
        format: FormatKind::Rgb888,
        tile: (64, 32),
        dither: 0,
        depth: true,
        wid: false,
        clear: Clear::default(),
        aa: AaKind::None,
        cull: tilerast::command::Cull::None,
    }
}

/// The three methods' command lists ([`METHODS`] order) and exact Phong's
/// shading per triangle for a mesh.
pub struct Built {
    /// Gouraud, fast Phong and Taylor command lists.
    pub lists: [Vec<Command>; 3],
    /// Exact Phong's shading, by index into the Gouraud list.
    pub phong: HashMap<usize, PhongTri>,
}

impl Built {
    /// Exact Phong at pixel centres (f64, unrounded): the reference.
    pub fn exact(&self) -> RefFrame {
        reference::render_shaded(&config(), &self.lists[0], &|k, w| {
            self.phong.get(&k).map(|t| t.exact(w))
        })
    }
}

/// Builds the three methods' lists for `obj` under `spec` (its shading
/// field is ignored) on [`config`]'s screen.
pub fn build(obj: &tilerast_sim::obj::Obj, spec: &MeshSpec) -> Built {
    let list = |shading| {
        let spec = MeshSpec {
            shading,
            ..spec.clone()
        };
        let (mut out, mut edges, mut tags) = (Vec::new(), Vec::new(), 0);
        let st = mesh::build(obj, &spec, (240, 240), &mut out, &mut edges, &mut tags);
        (out, st.phong)
    };
    let (gouraud, phong) = list(ShadingKind::Gouraud);
    let (fast, _) = list(ShadingKind::FastPhong);
    let phong: HashMap<usize, PhongTri> = phong.into_iter().collect();
    let byte = |c: [f64; 3]| {
        let q = c.map(|v| v.round().clamp(0.0, 255.0) as u8);
        Rgb::new(q[0], q[1], q[2])
    };
    let taylor = gouraud
        .iter()
        .enumerate()
        .map(|(k, c)| match (c, phong.get(&k).and_then(|p| p.taylor())) {
            (Command::Triangle { v, state }, Some((at, mid))) => {
                let q = std::array::from_fn(|i| {
                    let mut vi = v[i];
                    vi.color = byte(at[i]);
                    QuadVertex::new(vi, byte(mid[i]))
                });
                Command::Quadratic {
                    alpha: 255,
                    v: q,
                    state: *state,
                }
            }
            _ => *c,
        })
        .collect();
    Built {
        lists: [gouraud, fast, taylor],
        phong,
    }
}

fn luminance(c: [f64; 3]) -> f64 {
    0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]
}

/// Centroid of the pixels within 2 of the brightest covered luminance.
fn highlight(px: &[[f64; 3]], covered: &[bool], w: usize) -> (f64, f64) {
    let top = px
        .iter()
        .zip(covered)
        .filter(|(_, c)| **c)
        .map(|(p, _)| luminance(*p))
        .fold(0.0, f64::max);
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0f64);
    for (i, p) in px.iter().enumerate() {
        if covered[i] && luminance(*p) >= top - 2.0 {
            sx += (i % w) as f64;
            sy += (i / w) as f64;
            n += 1.0;
        }
    }
    (sx / n.max(1.0), sy / n.max(1.0))
}

/// Whether some of the six points of the quadratic are lit by the first
/// light and some not: the triangle straddles the terminator.
fn straddles(p: &PhongTri) -> bool {
    let Some((dir, _, _)) = p.lights.lights.first() else {
        return false;
    };
    let d = |n: [f64; 3]| (0..3).map(|k| n[k] * dir[k]).sum::<f64>() > 0.0;
    let mids =
        [(0, 1), (1, 2), (2, 0)].map(|(a, b)| std::array::from_fn(|k| p.n[a][k] + p.n[b][k]));
    let lit: Vec<bool> = p.n.iter().chain(&mids).map(|n| d(*n)).collect();
    lit.iter().any(|l| *l) && !lit.iter().all(|l| *l)
}

fn spread(p: &PhongTri) -> f64 {
    let mut m: f64 = 0.0;
    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
        let d: f64 = (0..3).map(|k| p.n[a][k] * p.n[b][k]).sum();
        m = m.max(d.clamp(-1.0, 1.0).acos().to_degrees());
    }
    m
}

/// Measures one mesh under `spec` (its shading field is ignored).
pub fn measure(
    name: &str,
    obj: &tilerast_sim::obj::Obj,
    spec: &MeshSpec,
    runs: usize,
) -> Result<(Row, [Image; 4]), String> {
    let cfg = config();
    let b = build(obj, spec);
    let exact = b.exact();
    let covered: Vec<bool> = exact.depth.iter().map(|d| *d < 65535.0).collect();
    let n_cov = covered.iter().filter(|c| **c).count().max(1);
    let w = cfg.width as usize;
    let hl_exact = highlight(&exact.color, &covered, w);
    // Which command each pixel shows, and whether it is smooth.
    let ids = reference::render_shaded(&cfg, &b.lists[0], &|k, _| {
        Some([(k & 255) as f64, ((k >> 8) & 255) as f64, (k >> 16) as f64])
    });
    let smooth_cmd = |k: usize| {
        let quad = matches!(b.lists[1].get(k), Some(Command::Quadratic { .. }));
        quad && b.phong.get(&k).is_some_and(|p| !straddles(p))
    };
    let smooth: Vec<bool> = ids
        .color
        .iter()
        .map(|c| smooth_cmd(c[0] as usize | (c[1] as usize) << 8 | (c[2] as usize) << 16))
        .collect();
    let kinked = (0..covered.len())
        .filter(|&i| covered[i] && !smooth[i])
        .count() as f64
        / n_cov as f64;
    let spreads: Vec<f64> = b.phong.values().map(spread).collect();
    let slivers = b.lists[1]
        .iter()
        .filter(|c| match c {
            Command::Quadratic { v, .. } => reference::sliver(v),
            _ => false,
        })
        .count();
    let mut methods = [Method::default(); 3];
    let mut images = Vec::new();
    for (m, list) in methods.iter_mut().zip(&b.lists) {
        let r = render_timed(&cfg, list, runs).map_err(|e| e.to_string())?;
        let px: Vec<[f64; 3]> = r.image.pixels.iter().map(|p| p.map(|v| v as f64)).collect();
        let (mut sse, mut over) = (0.0, 0usize);
        for i in (0..px.len()).filter(|&i| covered[i]) {
            let mut worst: f64 = 0.0;
            for (a, b) in px[i].iter().zip(&exact.color[i]) {
                let e = (a - b).abs();
                sse += e * e;
                worst = worst.max(e);
            }
            m.max = m.max.max(worst);
            if smooth[i] {
                m.smooth_max = m.smooth_max.max(worst);
            }
            over += (worst > TARGET_LSB) as usize;
        }
        m.eq8 = sse / n_cov as f64;
        m.over2 = over as f64 / n_cov as f64;
        if spec.specular {
            let h = highlight(&px, &covered, w);
            m.highlight = Some(((h.0 - hl_exact.0).powi(2) + (h.1 - hl_exact.1).powi(2)).sqrt());
        }
        let screen = (cfg.width as f64) * (cfg.height as f64);
        m.ns = r.ns_per_pixel.unwrap_or(0.0) * screen / n_cov as f64;
        images.push(r.image);
    }
    images.push(exact.to_image());
    let images: [Image; 4] = images.try_into().map_err(|_| "four images")?;
    let row = Row {
        scene: name.to_string(),
        specular: spec.specular,
        spread: (
            spreads.iter().cloned().fold(0.0, f64::max),
            spreads.iter().sum::<f64>() / spreads.len().max(1) as f64,
        ),
        triangles: b.lists[0].len(),
        slivers,
        kinked,
        methods,
    };
    Ok((row, images))
}

/// Sphere tessellations measured.
pub const SLICES: [u32; 7] = [6, 8, 12, 16, 24, 32, 48];

/// The spheres' and the teapot's view and light; `obj` names the mesh.
fn base(obj: &str) -> MeshSpec {
    MeshSpec {
        eye: [0.0, 0.4, 3.0],
        target: [0.0; 3],
        fov: 40.0,
        light: [0.6, 0.7, 0.8],
        ambient: 0.15,
        cull_back: true,
        ..MeshSpec::new(obj)
    }
}

/// The sphere of [`sphere`]`(slices)`, parsed, and its view and light.
pub fn sphere_scene(
    slices: u32,
    specular: bool,
) -> Result<(tilerast_sim::obj::Obj, MeshSpec), String> {
    let limits = tilerast_sim::Limits::default();
    // A folder of its own per call: tests in one process may build
    // spheres at once.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("tilerast-phong-{}-{call}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let (o, m) = sphere(slices);
    let obj = std::fs::write(dir.join("sphere.mtl"), m)
        .map_err(|e| e.to_string())
        .and_then(|_| {
            tilerast_sim::obj::parse(o.as_bytes(), "sphere.obj", Some(&dir), &limits)
                .map_err(|e| e.to_string())
        });
    let _ = std::fs::remove_dir_all(&dir);
    let spec = MeshSpec {
        specular,
        ..base("sphere.obj")
    };
    Ok((obj?, spec))
}

/// The seed's teapot from `models`, and its view and light.
pub fn teapot_scene(
    models: &Path,
    specular: bool,
) -> Result<(tilerast_sim::obj::Obj, MeshSpec), String> {
    let limits = tilerast_sim::Limits::default();
    let obj =
        tilerast_sim::obj::load(&models.join("teapot.obj"), &limits).map_err(|e| e.to_string())?;
    let spec = MeshSpec {
        eye: [0.0, 1.4, 3.2],
        target: [0.0, -0.05, 0.0],
        fov: 34.0,
        rotate_y: -30.0,
        light: [0.5, 0.8, 0.6],
        specular,
        ..base("teapot.obj")
    };
    Ok((obj, spec))
}

/// Every scene: the spheres (diffuse, then specular) and the teapot from
/// `models` (both materials). Returns the rows and a picture per scene
/// (Gouraud, fast Phong, Taylor, exact side by side).
pub fn run(models: &Path, runs: usize) -> Result<(Vec<Row>, Vec<[Image; 4]>), String> {
    let (mut rows, mut pics) = (Vec::new(), Vec::new());
    for specular in [false, true] {
        for slices in SLICES {
            let (obj, spec) = sphere_scene(slices, specular)?;
            let (r, p) = measure(&format!("sphere {slices}"), &obj, &spec, runs)?;
            rows.push(r);
            pics.push(p);
        }
    }
    for specular in [false, true] {
        let (obj, spec) = teapot_scene(models, specular)?;
        let (r, p) = measure("teapot", &obj, &spec, runs)?;
        rows.push(r);
        pics.push(p);
    }
    Ok((rows, pics))
}

/// The largest spread of normals (degrees) of a diffuse sphere on which
/// fast Phong stays within [`TARGET_LSB`], with every finer one.
pub fn domain(rows: &[Row]) -> Option<f64> {
    let mut spheres: Vec<&Row> = rows
        .iter()
        .filter(|r| !r.specular && r.scene.starts_with("sphere"))
        .collect();
    spheres.sort_by(|a, b| a.spread.0.total_cmp(&b.spread.0));
    let mut ok = None;
    for r in spheres {
        if r.methods[1].smooth_max > TARGET_LSB {
            break;
        }
        ok = Some(r.spread.0);
    }
    ok
}

/// The Markdown report.
pub fn report(rows: &[Row], chart: &Path, pictures: &Path) -> String {
    let mut md = String::from(
        "# Fast Phong against exact Phong and Gouraud\n\n\
         Regenerate with `cargo xtask bench` (or `tilerast-lab phong-report`). Seed 001 §IV.2 \
         (the RE's fast Phong). Every method is drawn by the core except exact Phong, the f64 \
         reference: normal interpolated with screen-space weights and normalised per pixel, lit as \
         the geometry stage lights a vertex. *Fast Phong (ours)* lights the vertices and the edge \
         midpoints and draws the quadratic through the six colours; *Taylor* is Bishop and \
         Weimer's second-order expansion about the centroid, evaluated at the same six points on \
         the host and drawn by the same command (same per-pixel cost). 240x240 RGB888, no dither; \
         errors over the covered pixels, in 8-bit LSB.\n\n",
    );
    if let Some(d) = domain(rows) {
        md += &format!(
            "**Domain**: on the diffuse spheres fast Phong stays within {TARGET_LSB} LSB of exact \
             Phong, away from the terminator, while the normals of a triangle spread by up to \
             **{d:.0}°** (largest angle between two of its vertex normals).\n\n"
        );
    }
    md += "Columns: the largest channel error over every covered pixel, then away from \
           the terminator and creases (triangles whose six points are not all lit or all \
           unlit by the light — the kink of `max(0, N·L)`, which no smooth interpolant \
           follows — or with vertex normals 90° apart, which fast Phong draws Gouraud-shaded; \
           *kinked* is their share of the pixels).\n\n";
    md += "| scene | material | triangles (slivers) | spread max / mean | kinked | method | max error | max, smooth | eq. 8 / px | > 2 LSB | highlight offset | host ns/px |\n";
    md += "| --- | --- | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for r in rows {
        for (k, m) in r.methods.iter().enumerate() {
            let first = k == 0;
            md += &format!(
                "| {} | {} | {} | {} | {} | {} | {:.1} | {:.1} | {:.2} | {:.2}% | {} | {:.1} |\n",
                if first { r.scene.as_str() } else { "" },
                if first {
                    if r.specular {
                        "specular"
                    } else {
                        "diffuse"
                    }
                } else {
                    ""
                },
                if first {
                    format!("{} ({})", r.triangles, r.slivers)
                } else {
                    String::new()
                },
                if first {
                    format!("{:.1}° / {:.1}°", r.spread.0, r.spread.1)
                } else {
                    String::new()
                },
                if first {
                    format!("{:.1}%", r.kinked * 100.0)
                } else {
                    String::new()
                },
                METHODS[k],
                m.max,
                m.smooth_max,
                m.eq8,
                m.over2 * 100.0,
                m.highlight.map_or("—".into(), |h| format!("{h:.1} px")),
                m.ns,
            );
        }
    }
    md +=
        &format!(
        "\n![max error against spread]({})\n\n![Gouraud, fast Phong, Taylor, exact Phong]({})\n",
        chart.file_name().map_or("".into(), |f| f.to_string_lossy()),
        pictures.file_name().map_or("".into(), |f| f.to_string_lossy()),
    );
    md
}

/// Largest error against the spread of normals, per method, on the
/// spheres (diffuse solid, specular dashed), log scale.
pub fn chart(rows: &[Row]) -> Result<Image, String> {
    let colors = [
        RGBColor(200, 60, 40),
        RGBColor(30, 110, 200),
        RGBColor(40, 160, 80),
    ];
    let top = rows
        .iter()
        .flat_map(|r| r.methods.iter().map(|m| m.max))
        .fold(4.0, f64::max);
    let right = rows.iter().map(|r| r.spread.0).fold(10.0, f64::max) * 1.05;
    plot(720, 420, |area| {
        let mut ch = ChartBuilder::on(area)
            .caption(
                "Largest error vs exact Phong, spheres (solid: diffuse, dashed: specular)",
                (SANS, 16),
            )
            .margin(12)
            .x_label_area_size(34)
            .y_label_area_size(54)
            .build_cartesian_2d(0.0..right, (0.1..top * 1.5).log_scale())
            .map_err(err)?;
        ch.configure_mesh()
            .x_desc("largest spread of a triangle's normals, degrees")
            .y_desc("max error, LSB")
            .label_style((SANS, 12))
            .draw()
            .map_err(err)?;
        for (k, name) in METHODS.iter().enumerate() {
            let c = colors[k];
            for specular in [false, true] {
                let mut pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.specular == specular && r.scene.starts_with("sphere"))
                    .map(|r| (r.spread.0, r.methods[k].max.max(0.1)))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                let style = c.stroke_width(2);
                if specular {
                    ch.draw_series(DashedLineSeries::new(pts.clone(), 6, 4, style))
                        .map_err(err)?;
                } else {
                    ch.draw_series(LineSeries::new(pts.clone(), style))
                        .map_err(err)?
                        .label(*name)
                        .legend(move |(x, y)| {
                            PathElement::new([(x, y), (x + 16, y)], c.stroke_width(2))
                        });
                }
                ch.draw_series(pts.iter().map(|p| Circle::new(*p, 3, c.filled())))
                    .map_err(err)?;
            }
        }
        ch.draw_series(LineSeries::new(
            [(0.0, TARGET_LSB), (right, TARGET_LSB)],
            BLACK.stroke_width(1),
        ))
        .map_err(err)?
        .label("target: 2 LSB")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK));
        ch.configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .label_font((SANS, 12))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(err)?;
        Ok(())
    })
}

/// The pictures of the chosen scenes side by side, one row each:
/// Gouraud, fast Phong, Taylor, exact.
pub fn pictures(pics: &[&[Image; 4]]) -> Image {
    let rows: Vec<&[Image]> = pics.iter().map(|p| &p[..]).collect();
    crate::chart::grid(&rows)
}
