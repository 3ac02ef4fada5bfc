//! OBJ meshes to Gouraud triangles: the OBJ is quantised into the core's
//! model-space meshes ([`tilerast::geometry::Mesh`]) and drawn by the
//! core's geometry stage — camera, clipping, culling, lighting — exactly as
//! a firmware draws them. An f64 path (`geometry = "reference"`) stays as
//! the reference the core's two back ends are measured against.

use crate::meshtex::{FilterKind, TexImage, TexturedMesh, UvKind};
use std::path::Path;
use tilerast::frame::CommandSource;
use tilerast::geometry::{
    Angle, Cull, DrawOptions, Fx, Group, Lighting, Mat4, Material, Mesh, MeshData, Real, Scene,
    VertexSlot,
};
use tilerast::prelude::*;

/// Which geometry stage draws a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GeometryKind {
    /// The core's stage in `f32` (what a Cortex-M4F runs).
    #[default]
    F32,
    /// The core's stage in fixed point (what a Cortex-M0 runs).
    Fixed,
    /// The f64 reference (no clipping: triangles crossing the near plane
    /// are dropped).
    Reference,
}

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
    /// The geometry stage: `"f32"` (default), `"fixed"` or `"reference"`.
    #[serde(default)]
    pub geometry: GeometryKind,
    /// Add the `.mtl` specular term (`Ks`, `Ns`; Blinn-Phong per vertex).
    #[serde(default)]
    pub specular: bool,
    /// Shading between the vertices: `"gouraud"` (default) or
    /// `"fast_phong"` (the RE's quadratic shading, seed 001 §IV.2).
    #[serde(default)]
    pub shading: ShadingKind,
    /// A PNG texture for every group, relative to the scene file
    /// (default: each group's `.mtl` `map_Kd`, if any). Textured groups
    /// are lit white and modulate the texel ([`crate::meshtex`]).
    pub texture: Option<String>,
    /// Texture coordinates: `"obj"` (the file's `vt`, default),
    /// `"spherical"` or `"cylindrical"` (projected, for models without).
    #[serde(default)]
    pub uv: UvKind,
    /// Repeats of the texture across the coordinates, `[u, v]`.
    #[serde(default = "default_uv_scale")]
    pub uv_scale: [f64; 2],
    /// Texel filter: `"bilinear"` (default) or `"nearest"`.
    #[serde(default)]
    pub filter: FilterKind,
}

/// How the core's geometry stage shades a mesh ([`tilerast::geometry::Shading`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShadingKind {
    /// Lit at the vertices, interpolated linearly.
    #[default]
    Gouraud,
    /// Lit at the vertices and edge midpoints, interpolated quadratically.
    FastPhong,
}

impl From<ShadingKind> for tilerast::geometry::Shading {
    fn from(k: ShadingKind) -> Self {
        match k {
            ShadingKind::Gouraud => tilerast::geometry::Shading::Gouraud,
            ShadingKind::FastPhong => tilerast::geometry::Shading::FastPhong,
        }
    }
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

fn default_uv_scale() -> [f64; 2] {
    [1.0, 1.0]
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
    /// Triangles dropped (the reference path: behind the near plane or
    /// beyond the guard band; the core clips them instead).
    pub dropped: usize,
    /// Triangles clipped against the near/far planes or the guard band.
    pub clipped: usize,
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
    /// Exact Phong's shading ([`PhongTri`]) of the lit, unclipped triangle
    /// commands this mesh pushed, by their index in the command list
    /// (the core geometry back ends only).
    pub phong: Vec<(usize, PhongTri)>,
    /// The textures its textured commands index, in order.
    pub textures: Vec<TexImage>,
    /// Textured triangles drawn.
    pub textured: usize,
    /// Pieces of textured groups' triangles drawn untextured (clipped by
    /// the geometry stage).
    pub untextured: usize,
}

pub use crate::silhouette::{flag_silhouettes, silhouette_edges};

/// The next object tag (wrapping past 65535 back to 1).
pub(crate) fn next_tag(tags: &mut u16) -> u16 {
    *tags = tags.checked_add(1).unwrap_or(1);
    *tags
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
    let spec = MeshSpec {
        texture: spec
            .texture
            .as_ref()
            .map(|t| base.join(t).to_string_lossy().into_owned()),
        ..spec.clone()
    };
    Ok(build(&obj, &spec, screen, out, edges, tags))
}

/// One OBJ group after the geometry stage: its projected vertices (`None`
/// outside the depth range or guard band), its triangles as drawn (culled
/// and clipped), the edges of its front faces, and its state.
struct Projected {
    verts: Vec<Option<Vertex>>,
    /// Triangle commands (Gouraud or quadratic), with their exact Phong
    /// shading where known and, for whole (unclipped) triangles, their
    /// OBJ vertices.
    tris: Vec<(Command, Option<PhongTri>, Option<[u32; 3]>)>,
    wire: std::collections::BTreeSet<(u32, u32)>,
    kd: V3,
    state: State,
}

/// The unit-cube fit of the finite vertices (like GLM's glmUnitize):
/// centre and scale.
fn unit_fit(obj: &crate::obj::Obj) -> (V3, f64) {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for m in &obj.models {
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
    (center, scale)
}

/// A group's positions in the unit cube of [`unit_fit`].
fn fitted(mesh: &crate::obj::Model, center: V3, scale: f64) -> Vec<V3> {
    mesh.positions
        .iter()
        .map(|p| std::array::from_fn(|k| (p[k] as f64 - center[k]) * scale))
        .collect()
}

/// Per-vertex normals of a group: the file's, or area-weighted face normals
/// of the fitted positions.
fn normals_of(mesh: &crate::obj::Model, pos: &[V3]) -> Vec<V3> {
    if !mesh.normals.is_empty() {
        return mesh
            .normals
            .iter()
            .map(|n| norm([n[0] as f64, n[1] as f64, n[2] as f64]))
            .collect();
    }
    let mut acc = vec![[0.0; 3]; pos.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| pos[i as usize]);
        let n = cross(sub(b, a), sub(c, a)); // area-weighted
        for &i in t {
            acc[i as usize] = std::array::from_fn(|k| acc[i as usize][k] + n[k]);
        }
    }
    acc.into_iter().map(norm).collect()
}

/// The material of a group: the spec's colour or the `.mtl`'s, ambient =
/// diffuse, and with `spec.specular` the `.mtl`'s `Ks`/`Ns` (or a white
/// highlight of exponent 32 when the file has none).
fn material_of(spec: &MeshSpec, obj: &crate::obj::Obj, mesh: &crate::obj::Model) -> (V3, Material) {
    let mtl = mesh.material.and_then(|i| obj.materials.get(i));
    let kd = match (spec.color, mtl.and_then(|m| m.diffuse)) {
        _ if texture_of(spec, obj, mesh).is_some() => [1.0; 3],
        (Some(c), _) => c.map(|v| v as f64 / 255.0),
        (None, Some(d)) => d.map(|v| v as f64),
        (None, None) => [0.8; 3],
    };
    let to_rgb = |c: V3| {
        let q = c.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8);
        Rgb::new(q[0], q[1], q[2])
    };
    let mut m = Material::diffuse(to_rgb(kd));
    if spec.specular {
        let ks = mtl
            .and_then(|m| m.specular)
            .map_or([1.0; 3], |k| k.map(|v| v as f64));
        m.ks = to_rgb(ks);
        m.ns = mtl
            .and_then(|m| m.shininess)
            .map_or(32.0, |n| n as f64)
            .round()
            .clamp(1.0, 255.0) as u8;
    }
    (kd, m)
}

/// The texture a group is drawn with: the spec's, else its material's
/// `map_Kd` — when it has texture coordinates to draw it with.
fn texture_of(
    spec: &MeshSpec,
    obj: &crate::obj::Obj,
    mesh: &crate::obj::Model,
) -> Option<std::path::PathBuf> {
    let path = spec.texture.as_ref().map(Into::into).or_else(|| {
        mesh.material
            .and_then(|i| obj.materials.get(i))
            .and_then(|m| m.diffuse_map.clone())
    })?;
    (spec.uv != UvKind::Obj || !mesh.texcoords.is_empty()).then_some(path)
}

/// Each group's texturing ([`TexturedMesh`]), loading its texture into
/// `textures` once per file; a texture that cannot be read leaves its
/// groups untextured, with a warning.
fn texturing(
    obj: &crate::obj::Obj,
    spec: &MeshSpec,
    screen: (u16, u16),
    textures: &mut Vec<TexImage>,
    warnings: &mut Vec<String>,
) -> Vec<Option<TexturedMesh>> {
    let (center, scale) = unit_fit(obj);
    let cam = RefCamera::new(spec, screen);
    let mut out = Vec::new();
    for mesh in &obj.models {
        let Some(path) = texture_of(spec, obj, mesh) else {
            let has_map = mesh
                .material
                .and_then(|i| obj.materials.get(i))
                .is_some_and(|m| m.diffuse_map.is_some());
            if (has_map || spec.texture.is_some()) && spec.uv == UvKind::Obj {
                warnings.push(format!(
                    "{}: group `{}` has no texture coordinates (vt); drawn untextured",
                    spec.obj, mesh.name
                ));
            }
            out.push(None);
            continue;
        };
        let tex = match textures.iter().position(|t| t.path == path) {
            Some(k) => k,
            None if textures.len() > u8::MAX as usize => {
                warnings.push(format!("{}: more than 256 textures", spec.obj));
                out.push(None);
                continue;
            }
            None => match TexImage::load(&path, spec.filter) {
                Ok(t) => {
                    textures.push(t);
                    textures.len() - 1
                }
                Err(e) => {
                    warnings.push(format!("{}: texture: {e}; drawn untextured", spec.obj));
                    out.push(None);
                    continue;
                }
            },
        };
        let pos = fitted(mesh, center, scale);
        let uv = match spec.uv {
            UvKind::Obj => mesh.texcoords.iter().map(|t| t.map(f64::from)).collect(),
            kind => crate::meshtex::projected_uv(kind, &pos),
        };
        let near = spec.clip[0];
        out.push(Some(TexturedMesh {
            tex: tex as u8,
            size: (textures[tex].width, textures[tex].height),
            uv,
            scale: spec.uv_scale,
            q: pos
                .iter()
                .map(|&p| {
                    let z = cam.depth(p);
                    (z >= near).then(|| 65535.0 * near / z)
                })
                .collect(),
            seam: spec.uv != UvKind::Obj,
        }));
    }
    out
}

/// The OBJ as core meshes in model space: positions fitted into the unit
/// cube and quantised to `i16`, normals to unit `i16`, one mesh group per
/// OBJ group (split where a mesh reaches 65,535 vertices or triangles).
/// Each entry: the encoded mesh, and per OBJ group its (mesh, mesh vertex)
/// of every OBJ vertex and its (mesh, first triangle, triangles) runs.
pub struct CoreMeshes {
    /// Encoded meshes ([`tilerast::geometry::Mesh`] format).
    pub meshes: Vec<Vec<u8>>,
    /// Per OBJ group, per OBJ vertex: the mesh and its vertex there.
    pub vertex_map: Vec<Vec<Option<(usize, u16)>>>,
    /// Per OBJ group: its triangles' runs (mesh, first triangle, count).
    pub runs: Vec<Vec<(usize, u16, u16)>>,
    /// Per OBJ group: the diffuse colour, 0..1.
    pub kd: Vec<V3>,
}

/// Quantises an OBJ into core meshes ([`CoreMeshes`]).
pub fn core_meshes(obj: &crate::obj::Obj, spec: &MeshSpec) -> CoreMeshes {
    let (center, scale) = unit_fit(obj);
    let q = |v: f64| (v * 32768.0).round().clamp(-32768.0, 32767.0) as i16;
    let mut out = CoreMeshes {
        meshes: Vec::new(),
        vertex_map: Vec::new(),
        runs: Vec::new(),
        kd: Vec::new(),
    };
    // The mesh being built.
    #[derive(Default)]
    struct Building {
        pos: Vec<[i16; 3]>,
        nrm: Vec<[i16; 3]>,
        groups: Vec<Group>,
        tris: Vec<[u16; 3]>,
    }
    impl Building {
        /// An empty group starting at the next triangle and vertex.
        fn open(&self, material: Material) -> Group {
            Group {
                first_triangle: self.tris.len() as u16,
                triangles: 0,
                first_vertex: self.pos.len() as u16,
                vertices: 0,
                material,
            }
        }
    }
    let flush = |b: &mut Building, out: &mut CoreMeshes| {
        if b.groups.is_empty() {
            return;
        }
        let data = MeshData {
            center: [0; 3],
            extent: 1 << 16,
            positions: &b.pos,
            normals: Some(&b.nrm),
            colors: None,
            groups: &b.groups,
            triangles: &b.tris,
        };
        let mut buf = vec![0; data.encoded_len()];
        data.encode(&mut buf).expect("sizes checked while building");
        out.meshes.push(buf);
        *b = Building::default();
    };
    let mut b = Building::default();
    for mesh in &obj.models {
        let pos = fitted(mesh, center, scale);
        let normals = normals_of(mesh, &pos);
        let (kd, material) = material_of(spec, obj, mesh);
        let mut map: Vec<Option<(usize, u16)>> = vec![None; pos.len()];
        let mut runs = Vec::new();
        let mut group: Option<Group> = None;
        for t in &mesh.triangles {
            let new_verts = t
                .iter()
                .filter(|&&i| map[i as usize].is_none_or(|(m, _)| m != out.meshes.len()))
                .count();
            if b.pos.len() + new_verts > u16::MAX as usize || b.tris.len() + 1 > u16::MAX as usize {
                if let Some(g) = group.take() {
                    runs.push((out.meshes.len(), g.first_triangle, g.triangles));
                    b.groups.push(g);
                }
                flush(&mut b, &mut out);
            }
            let g = group.get_or_insert(b.open(material));
            let here = out.meshes.len();
            let idx = t.map(|i| {
                let i = i as usize;
                match map[i] {
                    Some((m, v)) if m == here && v >= g.first_vertex => v,
                    _ => {
                        let v = b.pos.len() as u16;
                        b.pos.push(pos[i].map(q));
                        b.nrm.push(normals[i].map(|c| (c * 32767.0).round() as i16));
                        map[i] = Some((here, v));
                        v
                    }
                }
            });
            b.tris.push(idx);
            g.triangles += 1;
            g.vertices = b.pos.len() as u16 - g.first_vertex;
        }
        // Vertices only lines use join the group (never lit: lines take
        // the unlit diffuse colour).
        for l in &mesh.lines {
            for &i in l {
                let i = i as usize;
                if map[i].is_none() && b.pos.len() < u16::MAX as usize {
                    let g = group.get_or_insert(b.open(material));
                    let v = b.pos.len() as u16;
                    b.pos.push(pos[i].map(q));
                    b.nrm.push([0, 0, 32767]);
                    map[i] = Some((out.meshes.len(), v));
                    g.vertices = b.pos.len() as u16 - g.first_vertex;
                }
            }
        }
        if let Some(g) = group.take() {
            runs.push((out.meshes.len(), g.first_triangle, g.triangles));
            b.groups.push(g);
        }
        out.vertex_map.push(map);
        out.runs.push(runs);
        out.kd.push(kd);
    }
    flush(&mut b, &mut out);
    out
}

/// Places, lights and projects a read OBJ: its triangles (and line
/// elements) go to `out`, its silhouette edges to `edges` when
/// `spec.edge_aa`; one object tag per group. The geometry runs in the
/// core's stage ([`tilerast::geometry`], `f32` or fixed point per
/// `spec.geometry`), or in the f64 reference path.
pub fn build(
    obj: &crate::obj::Obj,
    spec: &MeshSpec,
    screen: (u16, u16),
    out: &mut Vec<Command>,
    edges: &mut Vec<Command>,
    tags: &mut u16,
) -> MeshStats {
    let mut stats = MeshStats {
        groups: obj.models.len(),
        warnings: obj.warnings.clone(),
        ..Default::default()
    };
    stats.vertices = obj.models.iter().map(|m| m.positions.len()).sum();
    stats.triangles = obj.models.iter().map(|m| m.triangles.len()).sum();
    let groups = match spec.geometry {
        GeometryKind::Reference => project_reference(obj, spec, screen, tags, &mut stats),
        GeometryKind::F32 => project_core::<f32>(obj, spec, screen, tags, &mut stats),
        GeometryKind::Fixed => project_core::<Fx>(obj, spec, screen, tags, &mut stats),
    };
    let texturing = texturing(obj, spec, screen, &mut stats.textures, &mut stats.warnings);
    let mut solids = Vec::new();
    for ((g, mesh), tex) in groups.iter().zip(&obj.models).zip(&texturing) {
        if spec.faces {
            for (cmd, phong, corners) in &g.tris {
                let mut cmd = *cmd;
                if let Some(st) = cmd.state_mut() {
                    *st = g.state;
                }
                let v = match cmd {
                    Command::Quadratic { v, .. } => v.map(|q| q.vertex()),
                    Command::Triangle { v, .. } => v,
                    _ => unreachable!("the geometry stage emits triangles"),
                };
                solids.push(v);
                if let Some(tex) = tex {
                    match corners.and_then(|c| tex.command(v, c, g.state)) {
                        Some(t) => {
                            cmd = t;
                            stats.textured += 1;
                        }
                        None => {
                            cmd = Command::Triangle { v, state: g.state };
                            stats.untextured += 1;
                        }
                    }
                } else if let Some(p) = phong {
                    stats.phong.push((out.len(), p.clone()));
                }
                out.push(cmd);
            }
        }
        // The OBJ's own line elements, in the group's unlit colour.
        for l in &mesh.lines {
            let (Some(a), Some(b)) = (g.verts[l[0] as usize], g.verts[l[1] as usize]) else {
                stats.dropped += 1;
                continue;
            };
            let c = g.kd.map(|k| (k * 255.0).round().clamp(0.0, 255.0) as u8);
            let line = LineCmd {
                p0: (a.x, a.y),
                p1: (b.x, b.y),
                z: [a.z, b.z],
                color: Rgb::new(c[0], c[1], c[2]),
                style: LineStyle::SOLID,
                antialias: spec.wire_aa,
            };
            if line.validate().is_ok() {
                out.push(Command::Line {
                    line,
                    state: g.state,
                });
                stats.obj_lines += 1;
            }
        }
        if let Some(rgb) = spec.wireframe {
            for &(i, j) in &g.wire {
                let (Some(a), Some(b)) = (g.verts[i as usize], g.verts[j as usize]) else {
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
                out.push(Command::Line {
                    line,
                    state: g.state,
                });
                stats.lines += 1;
            }
        }
    }
    if spec.edge_aa {
        let state = groups.first().map_or(State::default(), |g| g.state);
        for edge in silhouette_edges(&solids) {
            edges.push(Command::Edge { edge, state });
            stats.edges += 1;
        }
    }
    stats
}

/// A spec's camera in back end `S`: view, projection, viewport, lights and
/// the model matrix.
pub type Camera<S> = (Mat4<S>, Mat4<S>, Rect, Lighting<S>, Mat4<S>);

/// The camera of a spec, in back end `S`: view, projection, viewport,
/// lights and the model matrix (rotation about x, then y).
pub fn camera_of<S: Real>(
    spec: &MeshSpec,
    screen: (u16, u16),
) -> Result<Camera<S>, tilerast::Error> {
    let [vx, vy, vw, vh] = spec
        .viewport
        .unwrap_or([0, 0, screen.0 as i32, screen.1 as i32]);
    let s = |v: f64| -> S { S::from_q((v * 65536.0).round() as i64, 16) };
    let v3 = |v: [f64; 3]| v.map(s);
    let view = Mat4::look_at(v3(spec.eye), v3(spec.target), v3(spec.up))?;
    let aspect = s(vw as f64).div(s(vh as f64));
    let proj = Mat4::perspective(
        Angle::from_degrees_f32(spec.fov as f32),
        aspect,
        s(spec.clip[0]),
        s(spec.clip[1]),
    )?;
    let rect = Rect::new(vx, vy, vw.max(0) as u32, vh.max(0) as u32);
    let lighting = Lighting::white(v3(spec.light), s(spec.ambient))?;
    let model = Mat4::rotation_y(Angle::from_degrees_f32(spec.rotate_y as f32)).mul(
        &Mat4::rotation_x(Angle::from_degrees_f32(spec.rotate_x as f32)),
    );
    Ok((view, proj, rect, lighting, model))
}

/// Vertex cache slots for `meshes`.
fn slots_for(meshes: &[Mesh<'_>]) -> usize {
    meshes.iter().map(|m| m.vertices() as usize).sum()
}

/// A core scene of the spec's camera and light with one draw per mesh
/// (`None`, with a warning, when the camera is degenerate); a mesh the
/// stage refuses is left out with a warning.
fn draw_all<'a, S: Real>(
    slots: &'a mut [VertexSlot],
    meshes: &[Mesh<'a>],
    spec: &MeshSpec,
    screen: (u16, u16),
    warnings: &mut Vec<String>,
) -> Option<Scene<'a, S, 64>> {
    let (view, proj, rect, lighting, model) = match camera_of::<S>(spec, screen) {
        Ok(c) => c,
        Err(e) => {
            warnings.push(format!("{}: camera: {e}", spec.obj));
            return None;
        }
    };
    let mut scene: Scene<'_, S, 64> = Scene::new(slots);
    scene.set_camera(view, proj);
    if let Err(e) = scene.set_viewport(rect) {
        warnings.push(format!("{}: viewport: {e}", spec.obj));
        return None;
    }
    scene.set_lighting(lighting);
    let opts = DrawOptions {
        state: State {
            wid: spec.window,
            ..State::default()
        },
        cull: if spec.cull_back {
            Cull::Back
        } else {
            Cull::None
        },
        shading: spec.shading.into(),
        ..DrawOptions::default()
    };
    for (k, m) in meshes.iter().enumerate() {
        if let Err(e) = scene.draw(m, &model, &opts) {
            warnings.push(format!("{}: mesh part {k}: {e}", spec.obj));
        }
    }
    Some(scene)
}

/// The core geometry stage over the OBJ's meshes.
fn project_core<S: Real>(
    obj: &crate::obj::Obj,
    spec: &MeshSpec,
    screen: (u16, u16),
    tags: &mut u16,
    stats: &mut MeshStats,
) -> Vec<Projected> {
    let cm = core_meshes(obj, spec);
    let mut groups: Vec<Projected> = cm
        .kd
        .iter()
        .map(|&kd| Projected {
            verts: Vec::new(),
            tris: Vec::new(),
            wire: Default::default(),
            kd,
            state: State {
                wid: spec.window,
                tag: next_tag(tags),
                ..State::default()
            },
        })
        .collect();
    let parsed: Vec<Mesh<'_>> = cm
        .meshes
        .iter()
        .map(|b| Mesh::parse(b).expect("encoded by core_meshes"))
        .collect();
    let mut slots = vec![VertexSlot::EMPTY; slots_for(&parsed)];
    let Some(scene) = draw_all::<S>(&mut slots, &parsed, spec, screen, &mut stats.warnings) else {
        return groups;
    };
    let lights = std::rc::Rc::new(phong_lights(spec));
    let st = scene.stats();
    stats.culled = st.culled as usize;
    stats.clipped = st.clipped as usize;
    // Projected vertices per OBJ group.
    for (g, map) in groups.iter_mut().zip(&cm.vertex_map) {
        g.verts = map
            .iter()
            .map(|e| e.and_then(|(m, v)| scene.projected(m, v)))
            .collect();
    }
    // Triangles back to their OBJ group by key: mesh triangle -> run.
    let mut owner = Vec::new(); // (global first triangle, count, group, mesh, first)
    let mut bases = vec![0u32; parsed.len() + 1];
    for (k, m) in parsed.iter().enumerate() {
        bases[k + 1] = bases[k] + m.triangles() as u32;
    }
    for (gi, runs) in cm.runs.iter().enumerate() {
        for &(m, first, n) in runs {
            owner.push((bases[m] + first as u32, n as u32, gi, m, first));
        }
    }
    owner.sort();
    // Per group: (mesh, mesh vertex) -> OBJ vertex.
    let obj_index: Vec<std::collections::HashMap<(usize, u16), u32>> = cm
        .vertex_map
        .iter()
        .map(|map| {
            map.iter()
                .enumerate()
                .filter_map(|(i, e)| e.map(|mv| (mv, i as u32)))
                .collect()
        })
        .collect();
    let _ = scene.each_keyed(|key, cmd| {
        let tri = key >> 3;
        let at = owner.partition_point(|o| o.0 <= tri).saturating_sub(1);
        let Some(&(first_global, _, gi, m, first)) = owner.get(at) else {
            return;
        };
        if let Command::Triangle { .. } | Command::Quadratic { .. } = cmd {
            let g = &mut groups[gi];
            let t = parsed[m].triangle(first + (tri - first_global) as u16);
            // A whole (unclipped) triangle: its first piece, every vertex
            // projected; its OBJ vertices.
            let whole = key & 7 == 0 && t.iter().all(|&v| scene.projected(m, v).is_some());
            let corners = match t.map(|mv| obj_index[gi].get(&(m, mv)).copied()) {
                [Some(a), Some(b), Some(c)] if whole => Some([a, b, c]),
                _ => None,
            };
            let phong = whole
                .then(|| phong_tri(&parsed[m], first + (tri - first_global) as u16, &t, &lights))
                .flatten();
            g.tris.push((*cmd, phong, corners));
            // Its edges for the wireframe, as OBJ vertex indices.
            if let Some([a, b, c]) = corners {
                for (i, j) in [(a, b), (b, c), (c, a)] {
                    g.wire.insert((i.min(j), i.max(j)));
                }
            }
        }
    });
    groups
}

/// The f64 reference camera and light of a spec.
struct RefCamera {
    rx: f64,
    ry: f64,
    eye: V3,
    fwd: V3,
    right: V3,
    up: V3,
    f: f64,
    aspect: f64,
    vp: [f64; 4],
    clip: [f64; 2],
    light: V3,
    ambient: f64,
}

impl RefCamera {
    fn new(spec: &MeshSpec, screen: (u16, u16)) -> Self {
        let fwd = norm(sub(spec.target, spec.eye));
        let right = norm(cross(fwd, spec.up));
        let [vx, vy, vw, vh] = spec
            .viewport
            .unwrap_or([0, 0, screen.0 as i32, screen.1 as i32]);
        RefCamera {
            rx: spec.rotate_x.to_radians(),
            ry: spec.rotate_y.to_radians(),
            eye: spec.eye,
            fwd,
            right,
            up: cross(right, fwd),
            f: 1.0 / (spec.fov.to_radians() / 2.0).tan(),
            aspect: vw as f64 / vh as f64,
            vp: [vx as f64, vy as f64, vw as f64, vh as f64],
            clip: spec.clip,
            light: norm(spec.light),
            ambient: spec.ambient,
        }
    }

    /// The inverse of [`rotate`](Self::rotate): world to model space.
    fn unrotate(&self, p: V3) -> V3 {
        let (s, c) = self.ry.sin_cos();
        let p = [c * p[0] - s * p[2], p[1], s * p[0] + c * p[2]];
        let (s, c) = self.rx.sin_cos();
        [p[0], c * p[1] + s * p[2], -s * p[1] + c * p[2]]
    }

    /// Eye-space depth of a fitted model point (along the view direction).
    fn depth(&self, p: V3) -> f64 {
        dot(sub(self.rotate(p), self.eye), self.fwd)
    }

    fn rotate(&self, p: V3) -> V3 {
        let (s, c) = self.rx.sin_cos();
        let p = [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]];
        let (s, c) = self.ry.sin_cos();
        [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]]
    }

    /// A fitted model point and its normal: screen `x, y` (pixels,
    /// unrounded), depth in `[0, 1]` (0 at near, hyperbolic like OpenGL's
    /// window z) and the light factor (ambient + diffuse), or `None` in
    /// front of the near plane.
    fn vertex(&self, p: V3, n: V3) -> Option<(f64, f64, f64, f64)> {
        let (p, n) = (self.rotate(p), self.rotate(n));
        let d = sub(p, self.eye);
        let (cx, cy, cz) = (dot(d, self.right), dot(d, self.up), dot(d, self.fwd));
        let [near, far] = self.clip;
        if cz <= near {
            return None;
        }
        let (nx, ny) = (self.f / self.aspect * cx / cz, self.f * cy / cz);
        let zn = (far / (far - near)) * (1.0 - near / cz);
        let [vx, vy, vw, vh] = self.vp;
        let sx = vx + (nx + 1.0) / 2.0 * vw;
        let sy = vy + (1.0 - ny) / 2.0 * vh;
        let lit = self.ambient + (1.0 - self.ambient) * dot(n, self.light).max(0.0);
        Some((sx, sy, zn, lit))
    }
}

/// How far a geometry back end's vertices are from the f64 reference.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GeometryError {
    /// Vertices compared (those both place on screen and that a visible
    /// triangle uses, so the core lit them).
    pub vertices: usize,
    /// Largest screen position error, pixels (Euclidean).
    pub max_position: f64,
    /// Mean screen position error, pixels.
    pub mean_position: f64,
    /// Largest depth error, 16-bit LSB.
    pub max_depth: f64,
    /// Largest colour error, 8-bit LSB (any channel).
    pub max_color: f64,
}

/// Measures back end `S` of the core's geometry stage against the f64
/// reference (unrounded) on every vertex of an OBJ under `spec`: position
/// error includes the quantisation of the mesh (`2^-15` of its half-size)
/// and the rasterizer's 1/16-pixel coordinates.
pub fn geometry_error<S: Real>(
    obj: &crate::obj::Obj,
    spec: &MeshSpec,
    screen: (u16, u16),
) -> GeometryError {
    let (center, scale) = unit_fit(obj);
    let rf = RefCamera::new(spec, screen);
    let mut tags = 0;
    let mut stats = MeshStats::default();
    let groups = project_core::<S>(obj, spec, screen, &mut tags, &mut stats);
    let mut e = GeometryError::default();
    let mut sum = 0.0;
    for (mesh, g) in obj.models.iter().zip(&groups) {
        let fitted = fitted(mesh, center, scale);
        let normals = normals_of(mesh, &fitted);
        let (kd, _) = material_of(spec, obj, mesh);
        let used: std::collections::BTreeSet<u32> =
            g.wire.iter().flat_map(|&(a, b)| [a, b]).collect();
        for i in used {
            let i = i as usize;
            let (Some(v), Some((x, y, z, lit))) = (g.verts[i], rf.vertex(fitted[i], normals[i]))
            else {
                continue;
            };
            let (dx, dy) = (v.x.to_num::<f64>() - x, v.y.to_num::<f64>() - y);
            let d = (dx * dx + dy * dy).sqrt();
            e.vertices += 1;
            sum += d;
            e.max_position = e.max_position.max(d);
            e.max_depth = e.max_depth.max((v.z as f64 - z * 65535.0).abs());
            let c = [v.color.r, v.color.g, v.color.b];
            for k in 0..3 {
                let want = (kd[k] * lit * 255.0).clamp(0.0, 255.0);
                e.max_color = e.max_color.max((c[k] as f64 - want).abs());
            }
        }
    }
    e.mean_position = sum / e.vertices.max(1) as f64;
    e
}

/// The f64 reference path: camera, one directional light, no clipping
/// (triangles behind the near plane or beyond the guard band are dropped).
fn project_reference(
    obj: &crate::obj::Obj,
    spec: &MeshSpec,
    screen: (u16, u16),
    tags: &mut u16,
    stats: &mut MeshStats,
) -> Vec<Projected> {
    let (center, scale) = unit_fit(obj);
    let rf = RefCamera::new(spec, screen);
    let mut out = Vec::new();
    for mesh in &obj.models {
        let fitted = fitted(mesh, center, scale);
        let normals = normals_of(mesh, &fitted);
        let (kd, _) = material_of(spec, obj, mesh);
        let verts: Vec<Option<Vertex>> = fitted
            .iter()
            .zip(&normals)
            .map(|(&p, &n)| {
                let (sx, sy, zn, lit) = rf.vertex(p, n)?;
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
        let state = State {
            wid: spec.window,
            tag: next_tag(tags),
            ..State::default()
        };
        let mut g = Projected {
            verts,
            tris: Vec::new(),
            wire: Default::default(),
            kd,
            state,
        };
        for t in &mesh.triangles {
            match t.map(|i| g.verts[i as usize]) {
                [Some(a), Some(b), Some(c)] => {
                    let p = |v: Vertex| (v.x.to_bits() as i64, v.y.to_bits() as i64);
                    let (pa, pb, pc) = (p(a), p(b), p(c));
                    let area = (pb.0 - pa.0) * (pc.1 - pa.1) - (pb.1 - pa.1) * (pc.0 - pa.0);
                    // OBJ fronts wind counter-clockwise seen from outside:
                    // clockwise on the y-down screen, a negative area here.
                    if spec.cull_back && area >= 0 {
                        stats.culled += 1;
                        continue;
                    }
                    g.tris.push((
                        Command::Triangle {
                            v: [a, b, c],
                            state: g.state,
                        },
                        None,
                        Some(*t),
                    ));
                    for (i, j) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                        g.wire.insert((i.min(j), i.max(j)));
                    }
                }
                _ => stats.dropped += 1,
            }
        }
        out.push(g);
    }
    out
}

/// Reads an OBJ (within `limits`) and encodes it as one core mesh in model
/// space ([`tilerast::geometry::Mesh`]: fitted into the unit cube,
/// quantised), for a firmware's flash. A model too large for one mesh
/// (65,535 vertices or triangles) is refused.
pub fn export_mesh(path: &Path, limits: &crate::obj::Limits) -> crate::Result<Vec<u8>> {
    let obj = crate::obj::load(path, limits)?;
    let spec = MeshSpec::new(&path.to_string_lossy());
    let mut cm = core_meshes(&obj, &spec);
    match cm.meshes.len() {
        1 => Ok(cm.meshes.remove(0)),
        0 => Err(crate::Error::Unsupported(format!(
            "{}: no triangles or lines to export",
            path.display()
        ))),
        n => Err(crate::Error::Unsupported(format!(
            "{}: needs {n} meshes of at most 65,535 vertices and triangles; export writes one",
            path.display()
        ))),
    }
}

/// Writes `frames` frames of a mesh turning once about `y` (exactly the
/// firmware's [`tilerast_fw::spin`] animation, back end `S`) as an animated
/// PNG at `fps` frames per second; returns each frame's geometry stats.
pub fn animate<S: Real>(
    mesh_bytes: &[u8],
    frames: u32,
    fps: u16,
    out: &Path,
) -> crate::Result<Vec<tilerast::geometry::DrawStats>> {
    use embedded_graphics_core::pixelcolor::Rgb565;
    use tilerast_fw::spin;
    let mesh =
        Mesh::parse(mesh_bytes).map_err(|e| crate::Error::Unsupported(format!("mesh: {e}")))?;
    let mut slots = vec![VertexSlot::EMPTY; mesh.vertices() as usize];
    let mut tile: Tile<{ groups(64, 32) }, spin::SpinConfig> = Tile::new();
    let mut bins: Bins<16384, 32> = Bins::new();
    let side = spin::SIDE as u32;
    let file = std::fs::File::create(out).map_err(|e| crate::Error::io(out, e))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), side, side);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let png_err = |e: png::EncodingError| crate::Error::Unsupported(format!("png: {e}"));
    enc.set_animated(frames.max(1), 0).map_err(png_err)?;
    enc.set_frame_delay(1, fps.max(1)).map_err(png_err)?;
    let mut w = enc.write_header().map_err(png_err)?;
    let mut stats = Vec::new();
    for k in 0..frames.max(1) {
        let mut display = crate::PngDisplay::<Rgb565>::new(side, side);
        let f = spin::frame_into::<S, { groups(64, 32) }, 16384, 32, _>(
            &mesh,
            &mut slots,
            &mut tile,
            &mut bins,
            (64, 32),
            (k, frames.max(1)),
            &mut display,
            &mut || 0,
        )
        .map_err(|e| crate::Error::Unsupported(format!("frame {k}: {e}")))?;
        stats.push(f.geometry);
        w.write_image_data(display.image().pixels.as_flattened())
            .map_err(png_err)?;
    }
    w.finish().map_err(png_err)?;
    Ok(stats)
}

/// Host nanoseconds per vertex of a geometry stage on an OBJ (median of
/// `runs`): the core's vertex stage in back end `kind` (transform, cull,
/// light: [`Scene::draw`]), or the f64 reference's projection and lighting.
pub fn vertex_stage_ns(
    obj: &crate::obj::Obj,
    spec: &MeshSpec,
    screen: (u16, u16),
    kind: GeometryKind,
    runs: usize,
) -> f64 {
    fn core<S: Real>(cm: &CoreMeshes, spec: &MeshSpec, screen: (u16, u16)) -> Option<u32> {
        let parsed: Vec<Mesh<'_>> = cm
            .meshes
            .iter()
            .filter_map(|b| Mesh::parse(b).ok())
            .collect();
        let mut slots = vec![VertexSlot::EMPTY; slots_for(&parsed)];
        let mut warnings = Vec::new();
        let scene = draw_all::<S>(&mut slots, &parsed, spec, screen, &mut warnings)?;
        Some(scene.stats().vertices)
    }
    let cm = core_meshes(obj, spec);
    let mut times = Vec::new();
    let mut vertices = 1u32;
    for _ in 0..runs.max(1) {
        let t = std::time::Instant::now();
        let v = match kind {
            GeometryKind::F32 => core::<f32>(&cm, spec, screen),
            GeometryKind::Fixed => core::<Fx>(&cm, spec, screen),
            GeometryKind::Reference => {
                let (mut tags, mut st) = (0, MeshStats::default());
                let g = project_reference(obj, spec, screen, &mut tags, &mut st);
                Some(g.iter().map(|g| g.verts.len() as u32).sum())
            }
        };
        times.push(t.elapsed().as_nanos() as f64);
        vertices = v.unwrap_or(1).max(1);
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2] / vertices as f64
}

/// What exact Phong shades one triangle command with (`render --shading
/// phong`, the f64 reference of fast Phong): its vertices' unit normals
/// and colours and the draw's lights, all in model space as the core's
/// geometry stage lights them. The normal is interpolated linearly in
/// screen space (by the command's barycentric weights) and normalised at
/// every pixel: classic Phong shading.
#[derive(Debug, Clone)]
pub struct PhongTri {
    /// Unit normals at the command's vertices.
    pub n: [V3; 3],
    /// Diffuse colours at the vertices, `0..=255`.
    pub kd: [V3; 3],
    /// Ambient colours at the vertices, `0..=255`.
    pub ka: [V3; 3],
    /// Specular colour, `0..=255` (black: none).
    pub ks: V3,
    /// Specular exponent.
    pub ns: u8,
    /// The lights.
    pub lights: std::rc::Rc<PhongLights>,
}

/// Lights of a draw in model space (f64).
#[derive(Debug, Clone, Default)]
pub struct PhongLights {
    /// Per directional light: unit direction towards it, Blinn's half
    /// vector (zero: no highlight) and colour.
    pub lights: Vec<(V3, V3, V3)>,
    /// Ambient light per channel.
    pub ambient: V3,
}

impl PhongTri {
    /// The colour at weights `w` (command vertex order) for the unit normal
    /// `n`: ambient + Lambert + Blinn-Phong, as the core's geometry stage
    /// lights a vertex, unrounded and saturated to `0..=255`.
    pub fn lit(&self, n: V3, w: [f64; 3]) -> [f64; 3] {
        let (mut diff, mut spec) = ([0.0; 3], [0.0; 3]);
        for (dir, half, color) in &self.lights.lights {
            let ndl = dot(n, *dir);
            if ndl > 0.0 {
                let ndh = dot(n, *half);
                let p = if ndh > 0.0 {
                    ndh.powi(self.ns.max(1) as i32)
                } else {
                    0.0
                };
                for k in 0..3 {
                    diff[k] += color[k] * ndl;
                    spec[k] += color[k] * p;
                }
            }
        }
        let at = |c: &[V3; 3], k: usize| (0..3).map(|i| w[i] * c[i][k]).sum::<f64>();
        std::array::from_fn(|k| {
            let v = at(&self.ka, k) * self.lights.ambient[k]
                + at(&self.kd, k) * diff[k]
                + self.ks[k] * spec[k];
            v.clamp(0.0, 255.0)
        })
    }

    /// Exact Phong at weights `w`: the normal interpolated and normalised.
    pub fn exact(&self, w: [f64; 3]) -> [f64; 3] {
        let n = std::array::from_fn(|k| (0..3).map(|i| w[i] * self.n[i][k]).sum());
        self.lit(norm(n), w)
    }

    /// Bishop and Weimer's fast Phong (SIGGRAPH '86), the Taylor variant:
    /// the exact Phong colour expanded to second order about the
    /// triangle's centroid (screen-space interpolation makes it a function
    /// of the weights, affine in `x, y`, so this is their quadratic in
    /// `x, y`), evaluated at the vertices and edge midpoints — the six
    /// colours of the core's [`Command::Quadratic`] that draws exactly
    /// that quadratic. `None` where the expansion has no value (the
    /// interpolated normal vanishes at the centroid).
    pub fn taylor(&self) -> Option<([V3; 3], [V3; 3])> {
        // Jets in (w1, w2) with w0 = 1 - w1 - w2, about (1/3, 1/3).
        let w = [
            Jet::new(1.0 / 3.0, [-1.0, -1.0]),
            Jet::new(1.0 / 3.0, [1.0, 0.0]),
            Jet::new(1.0 / 3.0, [0.0, 1.0]),
        ];
        let lerp = |c: &[V3; 3], k: usize| {
            w.iter()
                .zip(c)
                .fold(Jet::c(0.0), |a, (wi, ci)| a.add(&wi.scale(ci[k])))
        };
        let n: [Jet; 3] = std::array::from_fn(|k| lerp(&self.n, k));
        let len = n[0].mul(&n[0]).add(&n[1].mul(&n[1])).add(&n[2].mul(&n[2]));
        if len.v <= 1e-12 {
            return None;
        }
        let inv = len.sqrt().recip();
        let nn: [Jet; 3] = std::array::from_fn(|k| n[k].mul(&inv));
        let dotj = |d: &V3| {
            nn[0]
                .scale(d[0])
                .add(&nn[1].scale(d[1]))
                .add(&nn[2].scale(d[2]))
        };
        let (mut diff, mut spec) = ([Jet::c(0.0); 3], [Jet::c(0.0); 3]);
        for (dir, half, color) in &self.lights.lights {
            let ndl = dotj(dir);
            // The branch taken at the centroid (the expansion point).
            if ndl.v > 0.0 {
                let ndh = dotj(half);
                let p = if ndh.v > 0.0 {
                    ndh.powi(self.ns.max(1) as u32)
                } else {
                    Jet::c(0.0)
                };
                for k in 0..3 {
                    diff[k] = diff[k].add(&ndl.scale(color[k]));
                    spec[k] = spec[k].add(&p.scale(color[k]));
                }
            }
        }
        let col: [Jet; 3] = std::array::from_fn(|k| {
            lerp(&self.ka, k)
                .scale(self.lights.ambient[k])
                .add(&lerp(&self.kd, k).mul(&diff[k]))
                .add(&spec[k].scale(self.ks[k]))
        });
        let at = |w1: f64, w2: f64| -> V3 {
            std::array::from_fn(|k| {
                col[k]
                    .eval(w1 - 1.0 / 3.0, w2 - 1.0 / 3.0)
                    .clamp(0.0, 255.0)
            })
        };
        // Vertices (1,0,0), (0,1,0), (0,0,1); midpoints of 01, 12, 20.
        Some((
            [at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0)],
            [at(0.5, 0.0), at(0.5, 0.5), at(0.0, 0.5)],
        ))
    }
}

/// A second-order jet in two variables: value, gradient and Hessian
/// (`xx, xy, yy`) — enough for an exact second-order Taylor expansion.
#[derive(Debug, Clone, Copy)]
struct Jet {
    v: f64,
    d: [f64; 2],
    h: [f64; 3],
}

impl Jet {
    fn new(v: f64, d: [f64; 2]) -> Jet {
        Jet { v, d, h: [0.0; 3] }
    }
    fn c(v: f64) -> Jet {
        Jet::new(v, [0.0; 2])
    }
    fn add(&self, o: &Jet) -> Jet {
        Jet {
            v: self.v + o.v,
            d: [self.d[0] + o.d[0], self.d[1] + o.d[1]],
            h: std::array::from_fn(|i| self.h[i] + o.h[i]),
        }
    }
    fn scale(&self, s: f64) -> Jet {
        Jet {
            v: self.v * s,
            d: self.d.map(|x| x * s),
            h: self.h.map(|x| x * s),
        }
    }
    fn mul(&self, o: &Jet) -> Jet {
        let (a, b) = (self, o);
        Jet {
            v: a.v * b.v,
            d: [a.d[0] * b.v + a.v * b.d[0], a.d[1] * b.v + a.v * b.d[1]],
            h: [
                a.h[0] * b.v + 2.0 * a.d[0] * b.d[0] + a.v * b.h[0],
                a.h[1] * b.v + a.d[0] * b.d[1] + a.d[1] * b.d[0] + a.v * b.h[1],
                a.h[2] * b.v + 2.0 * a.d[1] * b.d[1] + a.v * b.h[2],
            ],
        }
    }
    /// `f(self)` for `f` with value, first and second derivative `f0, f1, f2`.
    fn chain(&self, f0: f64, f1: f64, f2: f64) -> Jet {
        let d = self.d;
        Jet {
            v: f0,
            d: d.map(|x| f1 * x),
            h: [
                f1 * self.h[0] + f2 * d[0] * d[0],
                f1 * self.h[1] + f2 * d[0] * d[1],
                f1 * self.h[2] + f2 * d[1] * d[1],
            ],
        }
    }
    fn sqrt(&self) -> Jet {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s, -0.25 / (s * self.v))
    }
    fn recip(&self) -> Jet {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }
    fn powi(&self, e: u32) -> Jet {
        let n = e as f64;
        let p = |k: i32| self.v.powi(k);
        self.chain(
            p(e as i32),
            n * p(e as i32 - 1),
            n * (n - 1.0) * p(e as i32 - 2),
        )
    }
    fn eval(&self, x: f64, y: f64) -> f64 {
        self.v
            + self.d[0] * x
            + self.d[1] * y
            + 0.5 * (self.h[0] * x * x + 2.0 * self.h[1] * x * y + self.h[2] * y * y)
    }
}

/// The lights of `spec` in model space, as the core's geometry stage turns
/// them (`Lighting::white`: one light of intensity `1 - ambient`, Blinn's
/// half vector for a viewer at infinity along the camera axis).
fn phong_lights(spec: &MeshSpec) -> PhongLights {
    let rf = RefCamera::new(spec, (1, 1));
    let eye = norm(sub(spec.eye, spec.target));
    let l = rf.light;
    let half = norm(std::array::from_fn(|k| l[k] + eye[k]));
    PhongLights {
        lights: vec![(rf.unrotate(l), rf.unrotate(half), [1.0 - spec.ambient; 3])],
        ambient: [spec.ambient; 3],
    }
}

/// Exact Phong's data for triangle `t` (vertices `idx`) of a core mesh:
/// `None` when the mesh has no normals.
fn phong_tri(
    mesh: &Mesh<'_>,
    t: u16,
    idx: &[u16; 3],
    lights: &std::rc::Rc<PhongLights>,
) -> Option<PhongTri> {
    let group = (0..mesh.groups())
        .map(|g| mesh.group(g))
        .find(|g| t < g.first_triangle + g.triangles)?;
    let m = group.material;
    let c = |c: Rgb| [c.r, c.g, c.b].map(|v| v as f64);
    let mut n = [[0.0; 3]; 3];
    let (mut kd, mut ka) = ([[0.0; 3]; 3], [[0.0; 3]; 3]);
    for k in 0..3 {
        n[k] = norm(mesh.normal(idx[k])?.map(|v| v as f64 / 32767.0));
        let vc = mesh.color(idx[k]);
        kd[k] = c(vc.unwrap_or(m.kd));
        ka[k] = c(if vc.is_some() {
            vc.unwrap_or(m.kd)
        } else {
            m.ka
        });
    }
    Some(PhongTri {
        n,
        kd,
        ka,
        ks: c(m.ks),
        ns: m.ns,
        lights: lights.clone(),
    })
}
