//! The occlusion-culling workload (seed 004): a city of box buildings on a
//! ground slab, walked through by a camera down its middle street. The
//! buildings are unit cubes subdivided `SUB x SUB` per face, so the same
//! city comes in a "large triangles" (`SUB = 1`) and a "small triangles"
//! variant. Everything is made in code from a seed, so the host and every
//! board build the same scene, and the host checks a board's frames bit
//! for bit.

use crate::Clock;
use tilerast::geometry::{
    Angle, DrawOptions, Group, Lighting, Mat4, Material, Mesh, MeshData, Scene, Vec3, VertexSlot,
};
use tilerast::hash::Crc32;
use tilerast::occlusion::{Aabb, CullMode, CullStats, Culler, HiZ, KdTree, MeshObjects};
use tilerast::prelude::*;

/// Most subdivisions of a face the buffers below hold.
pub const MAX_SUB: usize = 8;
/// Vertices of a cube subdivided `MAX_SUB` times.
pub const MAX_VERTS: usize = 6 * (MAX_SUB + 1) * (MAX_SUB + 1);
/// Triangles of a cube subdivided `MAX_SUB` times.
pub const MAX_TRIS: usize = 12 * MAX_SUB * MAX_SUB;
/// Bytes of the encoded subdivided cube at most.
pub const MESH_BYTES: usize = 64 + MAX_VERTS * 12 + MAX_TRIS * 6 + 64;

/// A unit cube (`-0.5..=0.5`) with `sub x sub` quads a face, a normal per
/// face, one diffuse colour, encoded into `buf` ([`MESH_BYTES`]).
pub fn cube(sub: usize, color: Rgb, buf: &mut [u8]) -> Result<Mesh<'_>, Error> {
    if !(1..=MAX_SUB).contains(&sub) {
        return Err(Error::BadSize);
    }
    const H: i32 = 32767;
    let mut pos = [[0i16; 3]; MAX_VERTS];
    let mut nrm = [[0i16; 3]; MAX_VERTS];
    let mut tris = [[0u16; 3]; MAX_TRIS];
    let (mut nv, mut nt) = (0usize, 0usize);
    let k = sub as i32;
    for f in 0..6 {
        let (axis, sign) = (f / 2, if f % 2 == 0 { 1 } else { -1 });
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let base = nv as u16;
        for j in 0..=k {
            for i in 0..=k {
                let p = &mut pos[nv];
                p[axis] = (sign * H) as i16;
                // Counter-clockwise from outside: u flips on the negative face.
                p[u] = (sign * (-H + 2 * H * i / k)) as i16;
                p[v] = (-H + 2 * H * j / k) as i16;
                nrm[nv][axis] = (sign * H) as i16;
                nv += 1;
            }
        }
        let row = (k + 1) as u16;
        for j in 0..k as u16 {
            for i in 0..k as u16 {
                let a = base + j * row + i;
                tris[nt] = [a, a + 1, a + row + 1];
                tris[nt + 1] = [a, a + row + 1, a + row];
                nt += 2;
            }
        }
    }
    let data = MeshData {
        center: [0; 3],
        extent: 1 << 15,
        positions: &pos[..nv],
        normals: Some(&nrm[..nv]),
        colors: None,
        groups: &[Group {
            first_triangle: 0,
            triangles: nt as u16,
            first_vertex: 0,
            vertices: nv as u16,
            material: Material::diffuse(color),
        }],
        triangles: &tris[..nt],
    };
    let n = data.encode(buf)?;
    Mesh::parse(&buf[..n])
}

/// The building mesh (`sub` subdivisions) and the ground slab's, encoded
/// into `building` and `ground` ([`MESH_BYTES`] each).
pub fn meshes<'b>(
    sub: usize,
    building: &'b mut [u8],
    ground: &'b mut [u8],
) -> Result<(Mesh<'b>, Mesh<'b>), Error> {
    Ok((
        cube(sub, Rgb::new(200, 190, 170), building)?,
        cube(1, Rgb::new(90, 110, 90), ground)?,
    ))
}

/// A city: `side x side` blocks, one building each, plus the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct City {
    /// Blocks a side.
    pub side: u32,
    /// Subdivisions of a building face (1: large triangles).
    pub sub: usize,
    /// Seed of the buildings' sizes.
    pub seed: u32,
}

/// Eye position, view and projection matrices.
pub type Camera = (Vec3<f32>, Mat4<f32>, Mat4<f32>);

/// Block pitch, world units.
const PITCH: f32 = 2.0;

impl City {
    /// Objects: the buildings, then the ground slab.
    pub fn objects(&self) -> usize {
        (self.side * self.side) as usize + 1
    }

    /// Object `i`: its mesh (of [`meshes`]) and model matrix.
    pub fn item<'m>(
        &self,
        i: usize,
        building: Mesh<'m>,
        ground: Mesh<'m>,
    ) -> (Mesh<'m>, Mat4<f32>) {
        let mesh = if i + 1 == self.objects() {
            ground
        } else {
            building
        };
        (mesh, self.model(i))
    }

    /// The model matrix of object `i` (a building, or the ground last).
    pub fn model(&self, i: usize) -> Mat4<f32> {
        let n = self.side as usize;
        let half = self.side as f32 * PITCH / 2.0;
        if i >= n * n {
            return Mat4::translation([0.0, -0.05, 0.0]).mul(&Mat4::scale([
                2.0 * half + 4.0,
                0.1,
                2.0 * half + 4.0,
            ]));
        }
        let mut rng = crate::rng::Rng::new((self.seed as u64) << 32 | i as u64);
        let unit = |r: &mut crate::rng::Rng| (r.next_u64() >> 40) as f32 / (1u32 << 24) as f32;
        let (w, d) = (0.9 + 0.5 * unit(&mut rng), 0.9 + 0.5 * unit(&mut rng));
        let h = 0.8 + 3.2 * unit(&mut rng);
        let (cx, cz) = (
            (i % n) as f32 * PITCH - half + PITCH / 2.0,
            (i / n) as f32 * PITCH - half + PITCH / 2.0,
        );
        Mat4::translation([cx, h / 2.0, cz]).mul(&Mat4::scale([w, h, d]))
    }

    /// The camera at frame `k` of `frames`: walking down the street between
    /// the two middle columns, looking ahead and a little sideways.
    pub fn camera(&self, k: u32, frames: u32) -> (Vec3<f32>, Vec3<f32>) {
        let half = self.side as f32 * PITCH / 2.0;
        let t = k as f32 / frames.max(1) as f32;
        let z = half + 1.0 - t * (2.0 * half + 1.0);
        let x = if self.side.is_multiple_of(2) {
            0.0
        } else {
            PITCH / 2.0
        };
        let swing = 3.0 * (t * 2.0 - 1.0);
        ([x, 0.6, z], [x + swing, 0.9, z - 6.0])
    }

    /// The camera's matrices for a square `screen`.
    pub fn view(&self, k: u32, frames: u32) -> Result<Camera, Error> {
        let (eye, at) = self.camera(k, frames);
        Ok((
            eye,
            Mat4::look_at(eye, at, [0.0, 1.0, 0.0])?,
            Mat4::perspective(Angle::degrees(60), 1.0, 0.1, 40.0)?,
        ))
    }
}

/// The lights every city frame uses.
pub fn lighting() -> Result<Lighting<f32>, Error> {
    Lighting::white([0.5, 0.8, 0.3], 0.45)
}

/// The sky: the colour tiles are cleared to.
pub const SKY: Rgb = Rgb::new(150, 190, 230);

/// The firmware's city: 6 x 6 buildings subdivided twice (32 triangles
/// a face... of a 96 x 96 frame in 48 x 48 tiles).
pub const FW_CITY: City = City {
    side: 6,
    sub: 2,
    seed: 17,
};
/// The walk's tiles: the ST7789 preset's planes (RGB565, Z16, 4x4 dither)
/// under the plane contract, so the buildings' triangles go from the
/// vertex cache through the fused mesh path (`tilerast::tile`), large ones
/// too. (Under the exact contract, `St7789Config`, the M4 walk cost 1.60 M
/// instructions a frame; the frames hash the same, the dither hiding the
/// contracts' one-unit differences.)
pub type CityConfig = Planes<Rgb565Format, Depth16, NoWid, Bayer4, NoAa, PlaneContract>;

/// Frames the firmware walks.
pub const FW_FRAMES: u32 = 8;
/// Screen side, pixels.
pub const FW_SCREEN: u16 = 96;
const TILE: u16 = 48;
const G: usize = (TILE as usize * TILE as usize) / 8;
/// Objects of [`FW_CITY`].
pub const FW_OBJECTS: usize = 37;
/// Tree nodes for [`FW_CITY`].
pub const FW_NODES: usize = 73;
/// Vertex slots for [`FW_CITY`]: every building may be drawn.
pub const FW_SLOTS: usize = 37 * 6 * 9;

/// What one mode's walk cost and drew.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CityRun {
    /// Ticks, all frames (geometry, culling, raster; no flush).
    pub ticks: u32,
    /// Culling counts, summed over frames.
    pub stats: CullStats,
    /// Vertices the geometry stage transformed, summed over frames.
    pub vertices: u32,
    /// CRC32 of every frame's packed pixels, tile by tile.
    pub crc: u32,
}

/// Walks [`FW_CITY`] for [`FW_FRAMES`] frames with `mode` (threshold 0).
pub fn run_fw(
    mode: CullMode,
    slots: &mut [VertexSlot],
    clock: &mut impl Clock,
) -> Result<CityRun, Error> {
    let city = FW_CITY;
    let (mut bytes, mut gbytes) = ([0u8; MESH_BYTES], [0u8; MESH_BYTES]);
    let (building, ground) = meshes(city.sub, &mut bytes, &mut gbytes)?;
    if city.objects() != FW_OBJECTS {
        return Err(Error::BadSize);
    }
    let items: [(Mesh<'_>, Mat4<f32>); FW_OBJECTS] =
        core::array::from_fn(|i| city.item(i, building, ground));
    let boxes: [Aabb<f32>; FW_OBJECTS] =
        core::array::from_fn(|i| Aabb::of_mesh(&items[i].0, &items[i].1));
    let mut culler: Culler<f32, FW_NODES> = Culler::new(KdTree::build(&boxes)?);
    let mut tile: Tile<G, CityConfig> = Tile::new();
    let mut hiz: HiZ<36, 3> = HiZ::new();
    let mut frame = Tile::<G, CityConfig>::frame::<TILE, TILE>(FW_SCREEN, FW_SCREEN)?;
    frame.clear.color = SKY;
    let mut scene: Scene<'_, f32, FW_OBJECTS> = Scene::new(slots);
    scene.set_viewport(Rect::new(0, 0, FW_SCREEN as u32, FW_SCREEN as u32))?;
    scene.set_lighting(lighting()?);
    let mut run = CityRun::default();
    let mut crc = Crc32::default();
    for k in 0..FW_FRAMES {
        clock.lap();
        let mut ticks = 0;
        let (st, vertices) = walk_frame(
            city.view(k, FW_FRAMES)?,
            &items,
            &mut culler,
            &mut scene,
            (&frame, &mut tile, &mut hiz),
            mode,
            |t| {
                ticks += clock.lap();
                hash_tile(t, &mut crc);
                clock.lap();
                Ok::<(), Error>(())
            },
        )
        .map_err(|e| match e {
            FlushError::Raster(e) | FlushError::Target(e) => e,
            _ => Error::Malformed,
        })?;
        run.ticks += ticks;
        run.vertices += vertices;
        run.stats += st;
    }
    run.crc = crc.finish();
    Ok(run)
}

/// One frame of a walk through `items`: sets `scene`'s camera to `cam`
/// (the caller has set viewport and lights), renders every tile with
/// `mode` and hands each to `done`. Returns the culling counts and the
/// vertices the geometry stage transformed.
#[allow(clippy::too_many_arguments)]
pub fn walk_frame<
    'a,
    const N: usize,
    C,
    const B: usize,
    const SH: u32,
    const D: usize,
    const NODES: usize,
    E,
>(
    (eye, view, proj): Camera,
    items: &[(Mesh<'a>, Mat4<f32>)],
    culler: &mut Culler<f32, NODES>,
    scene: &mut Scene<'a, f32, D>,
    (frame, tile, hiz): (&Frame, &mut Tile<N, C>, &mut HiZ<B, SH>),
    mode: CullMode,
    done: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
) -> Result<(CullStats, u32), FlushError<E>>
where
    C: TileConfig,
{
    scene.clear();
    scene.set_camera(view, proj);
    let mut objects = MeshObjects::new(scene, items, DrawOptions::default())?;
    let st = culler.render(mode, frame, tile, hiz, eye, &mut objects, done)?;
    Ok((st, objects.scene().stats().vertices))
}

/// Feeds a tile's packed pixels, row by row, into `crc`.
pub fn hash_tile<const N: usize, C: TileConfig>(t: &Tile<N, C>, crc: &mut Crc32) {
    let a = t.area();
    for y in a.y..a.y + a.h as i32 {
        for x in a.x..a.x + a.w as i32 {
            crc.update(&t.raw(x, y).unwrap_or(0).to_le_bytes());
        }
    }
}
