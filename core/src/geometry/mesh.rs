//! Meshes in model space, read in place from flash or RAM: indexed
//! triangles, quantised positions, optional normals and colours, and groups
//! with materials (the object tags coverage antialiasing uses).
//!
//! One mesh in flash is drawn any number of times from any angle: the
//! per-frame state (transform, camera, lights) lives in
//! [`Scene`](super::Scene), never in the mesh.

use crate::error::Error;
use crate::format::Rgb;

const MAGIC: &[u8; 4] = b"TRMS";
const HEADER: usize = 28;
const GROUP: usize = 18;
const FLAG_NORMALS: u8 = 1;
const FLAG_COLORS: u8 = 2;

/// A surface's colours for the lighting of [`Scene`](super::Scene) (the
/// `.mtl` file's `Kd`, `Ka`, `Ks` and `Ns`).
///
/// ```
/// use tilerast::geometry::Material;
/// use tilerast::prelude::Rgb;
/// let m = Material::diffuse(Rgb::new(200, 40, 40));
/// assert_eq!((m.ka, m.ks), (m.kd, Rgb::new(0, 0, 0)));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Material {
    /// Diffuse colour.
    pub kd: Rgb,
    /// Ambient colour (scaled by the scene's ambient light).
    pub ka: Rgb,
    /// Specular colour (black: no highlight, and no specular cost).
    pub ks: Rgb,
    /// Specular exponent (Blinn-Phong), `1..=255`.
    pub ns: u8,
}

impl Material {
    /// A matte material: ambient = diffuse, no specular term.
    pub const fn diffuse(kd: Rgb) -> Self {
        Material {
            kd,
            ka: kd,
            ks: Rgb::new(0, 0, 0),
            ns: 1,
        }
    }
}

/// A run of triangles sharing a material (an OBJ group).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Group {
    /// First triangle.
    pub first_triangle: u16,
    /// Triangles.
    pub triangles: u16,
    /// First vertex its triangles use.
    pub first_vertex: u16,
    /// Vertices its triangles use.
    pub vertices: u16,
    /// Its material.
    pub material: Material,
}

/// A parsed mesh borrowing its bytes.
///
/// # Format
///
/// Little-endian, no alignment needed:
///
/// | offset | field | meaning |
/// | ---: | --- | --- |
/// | 0 | `b"TRMS"` | magic |
/// | 4 | `u8` | version, 1 |
/// | 5 | `u8` | flags: bit 0 normals, bit 1 colours |
/// | 6 | `nv: u16`, `nt: u16`, `ng: u16` | vertices, triangles, groups (`ng >= 1`) |
/// | 12 | `center: 3 x i32`, `extent: i32` | `Q16.16` model units, `extent > 0` |
/// | 28 | `nv x 3 x i16` | positions `q`: model point = `center + q / 32768 * extent` |
/// | | `nv x 3 x i16` | normals (if flagged), unit length = 32767 |
/// | | `nv x 3 x u8` | vertex colours (if flagged): the diffuse colour, replacing the group's |
/// | | `ng x 18 B` | groups: `first_triangle, triangles, first_vertex, vertices: u16`, `kd, ka, ks: 3 x u8`, `ns: u8` |
/// | | `nt x 3 x u16` | triangles, counter-clockwise seen from the front |
///
/// Groups cover the triangles in order, and a group's triangles use only
/// its own vertices (so each vertex is lit with one material).
/// [`Mesh::parse`] checks all of it once; reads afterwards cannot fail.
/// Positions quantised to the mesh's own box keep `2^-15` of its half-size:
/// 0.004 px on a 240-pixel model.
///
/// ```
/// use tilerast::geometry::{Group, Material, Mesh, MeshData};
/// use tilerast::prelude::Rgb;
/// let data = MeshData {
///     center: [0; 3],
///     extent: 1 << 16,
///     positions: &[[0, 0, 0], [32767, 0, 0], [0, 32767, 0]],
///     normals: Some(&[[0, 0, 32767]; 3]),
///     colors: None,
///     groups: &[Group { first_triangle: 0, triangles: 1, first_vertex: 0, vertices: 3,
///                       material: Material::diffuse(Rgb::new(255, 0, 0)) }],
///     triangles: &[[0, 1, 2]],
/// };
/// let mut buf = [0u8; 128];
/// let n = data.encode(&mut buf)?;
/// assert_eq!(n, data.encoded_len());
/// let mesh = Mesh::parse(&buf[..n])?;
/// assert_eq!((mesh.vertices(), mesh.triangles()), (3, 1));
/// assert_eq!(mesh.triangle(0), [0, 1, 2]);
/// assert!(Mesh::parse(&buf[..n - 1]).is_err());
/// # Ok::<(), tilerast::Error>(())
/// ```
#[derive(Clone, Copy)]
pub struct Mesh<'a> {
    bytes: &'a [u8],
    nv: u16,
    nt: u16,
    ng: u16,
    center: [i32; 3],
    extent: i32,
    normals: Option<usize>,
    colors: Option<usize>,
    groups: usize,
    tris: usize,
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    match b.get(at..at + 2) {
        Some(s) => u16::from_le_bytes([s[0], s[1]]),
        None => 0,
    }
}

fn i32_at(b: &[u8], at: usize) -> i32 {
    match b.get(at..at + 4) {
        Some(s) => i32::from_le_bytes([s[0], s[1], s[2], s[3]]),
        None => 0,
    }
}

fn i16x3_at(b: &[u8], at: usize) -> [i16; 3] {
    match b.get(at..at + 6) {
        Some(s) => [
            i16::from_le_bytes([s[0], s[1]]),
            i16::from_le_bytes([s[2], s[3]]),
            i16::from_le_bytes([s[4], s[5]]),
        ],
        None => [0; 3],
    }
}

fn rgb_at(b: &[u8], at: usize) -> Rgb {
    match b.get(at..at + 3) {
        Some(s) => Rgb::new(s[0], s[1], s[2]),
        None => Rgb::default(),
    }
}

impl<'a> Mesh<'a> {
    /// Parses and checks a mesh ([format](Mesh#format)): sizes, group runs,
    /// and every index inside its group's vertices. [`Error::Malformed`]
    /// otherwise.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        if bytes.len() < HEADER || &bytes[..4] != MAGIC || bytes[4] != 1 {
            return Err(Error::Malformed);
        }
        let flags = bytes[5];
        if flags & !(FLAG_NORMALS | FLAG_COLORS) != 0 {
            return Err(Error::Malformed);
        }
        let (nv, nt, ng) = (u16_at(bytes, 6), u16_at(bytes, 8), u16_at(bytes, 10));
        let center = [i32_at(bytes, 12), i32_at(bytes, 16), i32_at(bytes, 20)];
        let extent = i32_at(bytes, 24);
        if ng == 0 || extent <= 0 {
            return Err(Error::Malformed);
        }
        let mut at = HEADER + 6 * nv as usize;
        let normals = (flags & FLAG_NORMALS != 0).then(|| {
            let o = at;
            at += 6 * nv as usize;
            o
        });
        let colors = (flags & FLAG_COLORS != 0).then(|| {
            let o = at;
            at += 3 * nv as usize;
            o
        });
        let groups = at;
        let tris = groups + GROUP * ng as usize;
        if bytes.len() != tris + 6 * nt as usize {
            return Err(Error::Malformed);
        }
        let mesh = Mesh {
            bytes,
            nv,
            nt,
            ng,
            center,
            extent,
            normals,
            colors,
            groups,
            tris,
        };
        let mut next = 0u32;
        for g in 0..ng {
            let grp = mesh.group(g);
            let (t0, t1) = (
                grp.first_triangle as u32,
                grp.first_triangle as u32 + grp.triangles as u32,
            );
            let (v0, v1) = (
                grp.first_vertex as u32,
                grp.first_vertex as u32 + grp.vertices as u32,
            );
            if t0 != next || t1 > nt as u32 || v1 > nv as u32 {
                return Err(Error::Malformed);
            }
            for t in t0..t1 {
                if !mesh
                    .triangle(t as u16)
                    .iter()
                    .all(|&i| (v0..v1).contains(&(i as u32)))
                {
                    return Err(Error::Malformed);
                }
            }
            next = t1;
        }
        if next != nt as u32 {
            return Err(Error::Malformed);
        }
        Ok(mesh)
    }

    /// Vertices.
    pub fn vertices(&self) -> u16 {
        self.nv
    }
    /// Triangles.
    pub fn triangles(&self) -> u16 {
        self.nt
    }
    /// Groups.
    pub fn groups(&self) -> u16 {
        self.ng
    }
    /// Whether vertices carry normals (needed for lighting).
    pub fn has_normals(&self) -> bool {
        self.normals.is_some()
    }
    /// The box's centre, `Q16.16` model units.
    pub fn center(&self) -> [i32; 3] {
        self.center
    }
    /// The box's half-size, `Q16.16` model units.
    pub fn extent(&self) -> i32 {
        self.extent
    }
    /// Quantised position of vertex `i` (`[0; 3]` past the end).
    #[inline]
    pub fn position(&self, i: u16) -> [i16; 3] {
        i16x3_at(self.bytes, HEADER + 6 * i as usize)
    }
    /// Normal of vertex `i`, unit length 32767, if the mesh has normals.
    #[inline]
    pub fn normal(&self, i: u16) -> Option<[i16; 3]> {
        self.normals
            .map(|o| i16x3_at(self.bytes, o + 6 * i as usize))
    }
    /// Colour of vertex `i`, if the mesh has vertex colours.
    #[inline]
    pub fn color(&self, i: u16) -> Option<Rgb> {
        self.colors.map(|o| rgb_at(self.bytes, o + 3 * i as usize))
    }
    /// Group `g` (a default group past the end).
    pub fn group(&self, g: u16) -> Group {
        let at = self.groups + GROUP * g as usize;
        let b = self.bytes;
        Group {
            first_triangle: u16_at(b, at),
            triangles: u16_at(b, at + 2),
            first_vertex: u16_at(b, at + 4),
            vertices: u16_at(b, at + 6),
            material: Material {
                kd: rgb_at(b, at + 8),
                ka: rgb_at(b, at + 11),
                ks: rgb_at(b, at + 14),
                ns: b.get(at + 17).copied().unwrap_or(1),
            },
        }
    }
    /// Every triangle's vertex indices, in order: [`Self::triangle`] of
    /// `0..triangles()` read as one slice, with no bounds check a triangle
    /// (the vertex stage's cull loop reads all of them every frame).
    #[inline]
    pub(crate) fn triangle_list(&self) -> impl Iterator<Item = [u16; 3]> + '_ {
        let end = self.tris + 6 * self.nt as usize;
        self.bytes
            .get(self.tris..end)
            .unwrap_or(&[])
            .chunks_exact(6)
            .map(|s| {
                [
                    u16::from_le_bytes([s[0], s[1]]),
                    u16::from_le_bytes([s[2], s[3]]),
                    u16::from_le_bytes([s[4], s[5]]),
                ]
            })
    }
    /// The vertex indices of triangle `t` (`[0; 3]` past the end).
    #[inline]
    pub fn triangle(&self, t: u16) -> [u16; 3] {
        let at = self.tris + 6 * t as usize;
        // One bounds check for the three (binning and culling read every
        // triangle each frame: the M4 teapot's binning spent 48
        // instructions a triangle here with three, measured).
        match self.bytes.get(at..at + 6) {
            Some(s) => [
                u16::from_le_bytes([s[0], s[1]]),
                u16::from_le_bytes([s[2], s[3]]),
                u16::from_le_bytes([s[4], s[5]]),
            ],
            None => [0; 3],
        }
    }
}

impl core::fmt::Debug for Mesh<'_> {
    /// The counts, not the kilobytes of the mesh.
    ///
    /// ```
    /// use tilerast::geometry::{Mesh, CUBE_BYTES};
    /// let mut buf = [0u8; CUBE_BYTES];
    /// let cube = Mesh::cube(&mut buf)?;
    /// assert_eq!(format!("{cube:?}"), format!("Mesh {{ vertices: 24, triangles: 12, groups: 1, bytes: {CUBE_BYTES}, .. }}"));
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Mesh")
            .field("vertices", &self.nv)
            .field("triangles", &self.nt)
            .field("groups", &self.ng)
            .field("bytes", &self.bytes.len())
            .finish_non_exhaustive()
    }
}

/// A mesh's parts, to [`encode`](MeshData::encode) into the format above
/// (on the host, or at start-up into RAM).
#[derive(Debug, Clone, Copy)]
pub struct MeshData<'d> {
    /// Box centre, `Q16.16` model units.
    pub center: [i32; 3],
    /// Box half-size, `Q16.16` model units, `> 0`.
    pub extent: i32,
    /// Quantised positions ([format](Mesh#format)).
    pub positions: &'d [[i16; 3]],
    /// Normals, unit length 32767, one per position.
    pub normals: Option<&'d [[i16; 3]]>,
    /// Vertex colours, one per position.
    pub colors: Option<&'d [Rgb]>,
    /// Groups, covering the triangles in order.
    pub groups: &'d [Group],
    /// Triangles.
    pub triangles: &'d [[u16; 3]],
}

impl MeshData<'_> {
    /// Bytes [`encode`](Self::encode) writes.
    pub fn encoded_len(&self) -> usize {
        let nv = self.positions.len();
        HEADER
            + 6 * nv
            + self.normals.map_or(0, |_| 6 * nv)
            + self.colors.map_or(0, |_| 3 * nv)
            + GROUP * self.groups.len()
            + 6 * self.triangles.len()
    }

    /// Writes the mesh into `buf` and returns the bytes written; checks
    /// counts (below 65536, normals and colours one per vertex) and
    /// everything [`Mesh::parse`] checks.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        let nv = self.positions.len();
        let counts_ok = nv <= u16::MAX as usize
            && self.triangles.len() <= u16::MAX as usize
            && self.groups.len() <= u16::MAX as usize
            && self.normals.is_none_or(|n| n.len() == nv)
            && self.colors.is_none_or(|c| c.len() == nv);
        if !counts_ok {
            return Err(Error::Malformed);
        }
        let n = self.encoded_len();
        let out = buf.get_mut(..n).ok_or(Error::BufferTooSmall)?;
        let mut at = 0;
        let mut put = |bytes: &[u8]| {
            out[at..at + bytes.len()].copy_from_slice(bytes);
            at += bytes.len();
        };
        let flags = if self.normals.is_some() {
            FLAG_NORMALS
        } else {
            0
        } | if self.colors.is_some() {
            FLAG_COLORS
        } else {
            0
        };
        put(MAGIC);
        put(&[1, flags]);
        for c in [nv, self.triangles.len(), self.groups.len()] {
            put(&(c as u16).to_le_bytes());
        }
        for c in self.center.iter().chain(core::iter::once(&self.extent)) {
            put(&c.to_le_bytes());
        }
        let v3 = |v: &[i16; 3]| {
            let mut b = [0u8; 6];
            for (k, c) in v.iter().enumerate() {
                b[2 * k..2 * k + 2].copy_from_slice(&c.to_le_bytes());
            }
            b
        };
        self.positions.iter().for_each(|p| put(&v3(p)));
        self.normals.into_iter().flatten().for_each(|p| put(&v3(p)));
        self.colors
            .into_iter()
            .flatten()
            .for_each(|c| put(&[c.r, c.g, c.b]));
        for g in self.groups {
            for c in [g.first_triangle, g.triangles, g.first_vertex, g.vertices] {
                put(&c.to_le_bytes());
            }
            let m = &g.material;
            for c in [m.kd, m.ka, m.ks] {
                put(&[c.r, c.g, c.b]);
            }
            put(&[m.ns]);
        }
        for t in self.triangles {
            for i in t {
                put(&i.to_le_bytes());
            }
        }
        Mesh::parse(&buf[..n])?;
        Ok(n)
    }
}

/// Bytes of [`Mesh::cube`].
pub const CUBE_BYTES: usize = HEADER + 24 * 15 + GROUP + 12 * 6;

impl Mesh<'_> {
    /// A unit cube centred on the origin, a normal per face (24 vertices,
    /// 12 triangles), each face its own colour (vertex colours), encoded
    /// into `buf`: a first mesh to draw without exporting one.
    ///
    /// ```
    /// use tilerast::geometry::{Mesh, CUBE_BYTES};
    /// let mut buf = [0u8; CUBE_BYTES];
    /// let cube = Mesh::cube(&mut buf)?;
    /// assert_eq!((cube.vertices(), cube.triangles()), (24, 12));
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn cube(buf: &mut [u8; CUBE_BYTES]) -> Result<Mesh<'_>, Error> {
        const H: i16 = 32767;
        // Per face: normal axis and sign; its square's two in-plane axes.
        let faces: [(usize, i16, [u8; 3]); 6] = [
            (0, 1, [230, 60, 50]),
            (0, -1, [60, 200, 80]),
            (1, 1, [240, 220, 60]),
            (1, -1, [60, 120, 230]),
            (2, 1, [230, 230, 230]),
            (2, -1, [200, 80, 200]),
        ];
        let mut pos = [[0i16; 3]; 24];
        let mut nrm = [[0i16; 3]; 24];
        let mut col = [Rgb::default(); 24];
        let mut tris = [[0u16; 3]; 12];
        for (f, &(axis, sign, c)) in faces.iter().enumerate() {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for (j, (su, sv)) in [(-1, -1), (1, -1), (1, 1), (-1, 1)].into_iter().enumerate() {
                let i = 4 * f + j;
                pos[i][axis] = sign * H;
                // Counter-clockwise seen from outside: flip u on the negative face.
                pos[i][u] = su * sign * H;
                pos[i][v] = sv * H;
                nrm[i][axis] = sign * H;
                col[i] = Rgb::new(c[0], c[1], c[2]);
            }
            let b = 4 * f as u16;
            tris[2 * f] = [b, b + 1, b + 2];
            tris[2 * f + 1] = [b, b + 2, b + 3];
        }
        let data = MeshData {
            center: [0; 3],
            extent: 1 << 15, // half-size 0.5: a unit cube
            positions: &pos,
            normals: Some(&nrm),
            colors: Some(&col),
            groups: &[Group {
                first_triangle: 0,
                triangles: 12,
                first_vertex: 0,
                vertices: 24,
                material: Material::diffuse(Rgb::new(255, 255, 255)),
            }],
            triangles: &tris,
        };
        let n = data.encode(buf)?;
        Mesh::parse(&buf[..n])
    }
}
