//! OBJ meshes to Gouraud triangles: a camera, one directional light, and the
//! `.mtl` diffuse colours — the geometry side of the pipeline, in f64 on the
//! host (on a device this is the application's job).

use std::path::Path;
use tilerast::line::{EdgeCmd, Side};
use tilerast::prelude::*;

/// How a mesh is placed and lit.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// OBJ file, relative to the scene file.
    pub obj: String,
    /// Window ID the mesh draws into.
    #[serde(default)]
    pub window: u8,
    /// Screen rectangle `[x, y, w, h]` the camera maps to (default: the screen).
    pub viewport: Option<[i32; 4]>,
    /// Camera position (the model is scaled into the cube [-1, 1]^3).
    #[serde(default = "default_eye")]
    pub eye: [f64; 3],
    /// Point the camera looks at.
    #[serde(default)]
    pub target: [f64; 3],
    /// Camera up direction.
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov: f64,
    /// Near and far planes.
    #[serde(default = "default_clip")]
    pub clip: [f64; 2],
    /// Rotation about the model's y axis, degrees.
    #[serde(default)]
    pub rotate_y: f64,
    /// Rotation about the model's x axis, degrees (applied first).
    #[serde(default)]
    pub rotate_x: f64,
    /// Direction towards the light.
    #[serde(default = "default_light")]
    pub light: [f64; 3],
    /// Ambient fraction, 0..1.
    #[serde(default = "default_ambient")]
    pub ambient: f64,
    /// Colour for every group, overriding the `.mtl` diffuse colours.
    pub color: Option<[u8; 3]>,
    /// Draw the shaded faces (default true).
    #[serde(default = "default_true")]
    pub faces: bool,
    /// Also draw every edge once as a Bresenham line in this colour. Edges
    /// are Z-tested with `wire_bias` pulled towards the viewer, so they show
    /// on their own faces and hide behind others.
    pub wireframe: Option<[u8; 3]>,
    /// Draw the wireframe with two-point (Wu) antialiasing.
    #[serde(default)]
    pub wire_aa: bool,
    /// Depth bias of the wireframe, in 16-bit Z units.
    #[serde(default = "default_bias")]
    pub wire_bias: u16,
    /// Drop the triangles that face away from the camera (OBJ fronts wind
    /// counter-clockwise), as the geometry stage of a renderer with
    /// back-face culling would. Closed meshes look the same with fewer
    /// fragments; coverage antialiasing (the RUF buffer) needs it to see
    /// one surface per object in a pixel.
    #[serde(default)]
    pub cull_back: bool,
    /// Antialias the silhouette and open boundary of the shaded faces
    /// (seed 003 eq. 8): their edges are drawn after every solid of the scene.
    #[serde(default)]
    pub edge_aa: bool,
}

impl MeshSpec {
    /// The spec of `obj` with every other field at its scene-file default.
    ///
    /// ```
    /// let s = tilerast_sim::mesh::MeshSpec::new("teapot.obj");
    /// assert_eq!((s.fov, s.eye), (40.0, [0.0, 0.0, 3.0]));
    /// ```
    pub fn new(obj: &str) -> Self {
        use serde::Deserialize;
        let mut t = toml::Table::new();
        t.insert("obj".into(), toml::Value::String(obj.into()));
        MeshSpec::deserialize(toml::Value::Table(t)).expect("every other field has a default")
    }
}

fn default_true() -> bool {
    true
}
fn default_bias() -> u16 {
    256
}

fn default_eye() -> [f64; 3] {
    [0.0, 0.0, 3.0]
}
fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov() -> f64 {
    40.0
}
fn default_clip() -> [f64; 2] {
    [1.0, 5.0]
}
fn default_light() -> [f64; 3] {
    [0.4, 0.6, 1.0]
}
fn default_ambient() -> f64 {
    0.2
}

/// What loading a mesh produced.
#[derive(Debug, Clone, Default)]
pub struct MeshStats {
    /// Vertices in the file.
    pub vertices: usize,
    /// Triangles after triangulation.
    pub triangles: usize,
    /// Groups (objects) in the file.
    pub groups: usize,
    /// Triangles dropped: behind the near plane or beyond the guard band.
    pub dropped: usize,
    /// Wireframe edges drawn as lines.
    pub lines: usize,
    /// Silhouette and boundary edges found for edge antialiasing.
    pub edges: usize,
    /// Triangles culled as back faces.
    pub culled: usize,
    /// The OBJ's line elements (`l`), drawn as lines.
    pub obj_lines: usize,
    /// What the OBJ reader skipped or could not find, each naming its line.
    pub warnings: Vec<String>,
}

/// The edges of a triangle set that border something else on screen: those
/// of one triangle only (an open boundary) and those whose triangles all lie
/// on the same side of the edge (a fold: the silhouette). Edges are matched
/// by their end points' sub-pixel positions, so vertices an OBJ duplicates at
/// texture seams still join. Degenerate triangles take no part. The edge
/// gets the first triangle's vertices (colour and depth) and its side.
pub fn silhouette_edges(tris: &[[Vertex; 3]]) -> Vec<EdgeCmd> {
    use std::collections::BTreeMap;
    type Key = (i32, i32);
    let key = |v: &Vertex| (v.x.to_bits(), v.y.to_bits());
    // Per undirected edge: the first triangle's edge, and the sides seen.
    let mut seen: BTreeMap<(Key, Key), (EdgeCmd, bool, bool)> = BTreeMap::new();
    let mut order = Vec::new();
    for t in tris {
        let p = t.map(|v| (v.x.to_bits() as i64, v.y.to_bits() as i64));
        let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0);
        if area == 0 {
            continue;
        }
        for i in 0..3 {
            let e = EdgeCmd::of_triangle(t, i);
            let (a, b) = (key(&e.v[0]), key(&e.v[1]));
            let k = (a.min(b), a.max(b));
            // The side as seen from the edge's canonical direction.
            let right = (e.interior == Side::Right) == (a <= b);
            let entry = seen.entry(k).or_insert_with(|| {
                order.push(k);
                (e, false, false)
            });
            if right {
                entry.1 = true;
            } else {
                entry.2 = true;
            }
        }
    }
    order
        .iter()
        .filter_map(|k| {
            let (e, right, left) = seen[k];
            (right != left).then_some(e)
        })
        .collect()
}

type V3 = [f64; 3];
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: V3) -> V3 {
    let l = dot(a, a).sqrt();
    if l > 0.0 {
        a.map(|v| v / l)
    } else {
        a
    }
}

/// Loads an OBJ (within `limits`) and appends its triangles to `out`, one
/// command each ([`build`]).
pub fn load(
    spec: &MeshSpec,
    base: &Path,
    screen: (u16, u16),
    out: &mut Vec<Command>,
    edges: &mut Vec<Command>,
    tags: &mut u16,
    limits: &crate::obj::Limits,
) -> crate::Result<MeshStats> {
    let obj = crate::obj::load(&base.join(&spec.obj), limits)?;
    Ok(build(&obj, spec, screen, out, edges, tags))
}

/// Places, lights and projects a read OBJ: its triangles (and line
/// elements) go to `out`, its silhouette edges to `edges` when
/// `spec.edge_aa`; one object tag per group.
pub fn build(
    obj: &crate::obj::Obj,
    spec: &MeshSpec,
    screen: (u16, u16),
    out: &mut Vec<Command>,
    edges: &mut Vec<Command>,
    tags: &mut u16,
) -> MeshStats {
    let models = &obj.models;
    let mats = &obj.materials;
    let mut stats = MeshStats {
        groups: models.len(),
        warnings: obj.warnings.clone(),
        ..Default::default()
    };

    // Unit cube fit (like GLM's glmUnitize), over the finite vertices.
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for m in models {
        for (p, _) in m.positions.iter().zip(&m.finite).filter(|f| *f.1) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k] as f64);
                hi[k] = hi[k].max(p[k] as f64);
            }
        }
    }
    let center: V3 = std::array::from_fn(|k| (lo[k] + hi[k]) / 2.0);
    let scale = 2.0
        / (0..3)
            .map(|k| hi[k] - lo[k])
            .fold(f64::MIN_POSITIVE, f64::max);

    let (ry, rx) = (spec.rotate_y.to_radians(), spec.rotate_x.to_radians());
    let rotate = |p: V3| {
        let (s, c) = rx.sin_cos();
        let p = [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]];
        let (s, c) = ry.sin_cos();
        [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]]
    };
    // Camera basis.
    let fwd = norm(sub(spec.target, spec.eye));
    let right = norm(cross(fwd, spec.up));
    let up = cross(right, fwd);
    let [vx, vy, vw, vh] = spec
        .viewport
        .unwrap_or([0, 0, screen.0 as i32, screen.1 as i32]);
    let f = 1.0 / (spec.fov.to_radians() / 2.0).tan();
    let aspect = vw as f64 / vh as f64;
    let [near, far] = spec.clip;
    let light = norm(spec.light);

    let mut solids = Vec::new();
    for mesh in models {
        let pos: Vec<V3> = mesh
            .positions
            .iter()
            .map(|p| rotate(std::array::from_fn(|k| (p[k] as f64 - center[k]) * scale)))
            .collect();
        stats.vertices += pos.len();
        let normals: Vec<V3> = if !mesh.normals.is_empty() {
            mesh.normals
                .iter()
                .map(|n| norm(rotate([n[0] as f64, n[1] as f64, n[2] as f64])))
                .collect()
        } else {
            let mut acc = vec![[0.0; 3]; pos.len()];
            for t in &mesh.triangles {
                let [a, b, c] = t.map(|i| pos[i as usize]);
                let n = cross(sub(b, a), sub(c, a)); // area-weighted
                for &i in t {
                    acc[i as usize] = std::array::from_fn(|k| acc[i as usize][k] + n[k]);
                }
            }
            acc.into_iter().map(norm).collect()
        };
        let kd = match (
            spec.color,
            mesh.material
                .and_then(|i| mats.get(i))
                .and_then(|m| m.diffuse),
        ) {
            (Some(c), _) => c.map(|v| v as f64 / 255.0),
            (None, Some(d)) => d.map(|v| v as f64),
            (None, None) => [0.8; 3],
        };
        let verts: Vec<Option<Vertex>> = pos
            .iter()
            .zip(&normals)
            .map(|(&p, &n)| {
                let d = sub(p, spec.eye);
                let (cx, cy, cz) = (dot(d, right), dot(d, up), dot(d, fwd));
                if cz <= near {
                    return None;
                }
                let (nx, ny) = (f / aspect * cx / cz, f * cy / cz);
                // Depth: 0 at near, 65535 at far, perspective-correct like OpenGL's window z.
                let zn = (far / (far - near)) * (1.0 - near / cz);
                let sx = vx as f64 + (nx + 1.0) / 2.0 * vw as f64;
                let sy = vy as f64 + (1.0 - ny) / 2.0 * vh as f64;
                let lit = spec.ambient + (1.0 - spec.ambient) * dot(n, light).max(0.0);
                let color = kd.map(|k| (k * lit * 255.0).round().clamp(0.0, 255.0) as u8);
                let z = (zn.clamp(0.0, 1.0) * 65535.0).round() as u16;
                Vertex::try_from_f32(
                    sx as f32,
                    sy as f32,
                    z,
                    Rgb::new(color[0], color[1], color[2]),
                )
                .ok()
            })
            .collect();
        // One object tag per OBJ group (seed 000: fragments of one object
        // merge in the RUF buffer).
        let state = State {
            wid: spec.window,
            tag: crate::scene::next_tag(tags),
            ..State::default()
        };
        let mut wire = std::collections::BTreeSet::new();
        for t in &mesh.triangles {
            stats.triangles += 1;
            match t.map(|i| verts[i as usize]) {
                [Some(a), Some(b), Some(c)] => {
                    let area = |a: Vertex, b: Vertex, c: Vertex| {
                        let p = |v: Vertex| (v.x.to_bits() as i64, v.y.to_bits() as i64);
                        let (a, b, c) = (p(a), p(b), p(c));
                        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
                    };
                    // OBJ fronts wind counter-clockwise seen from outside:
                    // clockwise on the y-down screen, a negative area here.
                    if spec.cull_back && area(a, b, c) >= 0 {
                        stats.culled += 1;
                        continue;
                    }
                    if spec.faces {
                        out.push(Command::Triangle {
                            v: [a, b, c],
                            state,
                        });
                        solids.push(([a, b, c], state));
                    }
                    for (i, j) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                        wire.insert((i.min(j), i.max(j)));
                    }
                }
                _ => stats.dropped += 1,
            }
        }
        // The OBJ's own line elements, in the group's unlit colour.
        for l in &mesh.lines {
            let (Some(a), Some(b)) = (verts[l[0] as usize], verts[l[1] as usize]) else {
                stats.dropped += 1;
                continue;
            };
            let c = kd.map(|k| (k * 255.0).round().clamp(0.0, 255.0) as u8);
            let line = LineCmd {
                p0: (a.x, a.y),
                p1: (b.x, b.y),
                z: [a.z, b.z],
                color: Rgb::new(c[0], c[1], c[2]),
                style: LineStyle::SOLID,
                antialias: spec.wire_aa,
            };
            if line.validate().is_ok() {
                out.push(Command::Line { line, state });
                stats.obj_lines += 1;
            }
        }
        if let Some(rgb) = spec.wireframe {
            for (i, j) in wire {
                let (Some(a), Some(b)) = (verts[i as usize], verts[j as usize]) else {
                    continue;
                };
                let line = LineCmd {
                    p0: (a.x, a.y),
                    p1: (b.x, b.y),
                    z: [
                        a.z.saturating_sub(spec.wire_bias),
                        b.z.saturating_sub(spec.wire_bias),
                    ],
                    color: Rgb::new(rgb[0], rgb[1], rgb[2]),
                    style: LineStyle::SOLID,
                    antialias: spec.wire_aa,
                };
                out.push(Command::Line { line, state });
                stats.lines += 1;
            }
        }
    }
    if spec.edge_aa {
        let tris: Vec<[Vertex; 3]> = solids.iter().map(|(v, _)| *v).collect();
        let state = solids.first().map_or(State::default(), |(_, s)| *s);
        for edge in silhouette_edges(&tris) {
            edges.push(Command::Edge { edge, state });
            stats.edges += 1;
        }
    }
    stats
}
