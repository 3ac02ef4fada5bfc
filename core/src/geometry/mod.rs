//! Geometry on the device (pipeline stage 0): meshes in model space are
//! transformed, clipped, culled and lit here, so firmware can animate — the
//! "geometry processor" the seed's raster engine takes its triangles from.
//!
//! Per frame the application sets a camera ([`Mat4::look_at`],
//! [`Mat4::perspective`]), a viewport and lights, then [`Scene::draw`]s
//! meshes with model matrices. Each draw runs the **vertex stage once**:
//!
//! 1. the mesh's box is tested against the view frustum (eight corners,
//!    outcodes): a mesh wholly outside costs nothing more;
//! 2. every vertex is transformed to clip space, given an outcode (near,
//!    far, guard band) and, when inside, projected to the rasterizer's
//!    sub-pixel coordinates and 16-bit depth, into the **vertex cache**;
//! 3. one pass over the triangles culls back faces (integer signed area of
//!    the projected triangle) and marks the vertices that visible triangles
//!    use;
//! 4. only marked vertices are lit: ambient + Lambert diffuse + optional
//!    Blinn-Phong specular per directional light, computed in *model space*
//!    (the lights are turned into it once per draw), with `.mtl`-style
//!    [`Material`]s per group.
//!
//! The [`Scene`] is then a [`CommandSource`]: the frame pipeline bins and
//! replays its triangles by key, each read from three cache entries, so a
//! vertex shared by triangles in several tiles is transformed and lit once
//! per frame. Binning reads each triangle's box and winding straight from
//! the cache, and an unclipped Gouraud triangle goes from the cache to the
//! tile without a command being built ([`CommandSource::draw_keys`]); with
//! a tile under the plane contract
//! ([`PlaneContract`](crate::numeric::PlaneContract)) its setup, traversal
//! and planes are one 32-bit routine (`docs/contracts.md`). Triangles that cross the near or far plane or leave the guard
//! band are clipped in homogeneous space ([`clip`](self) module: split into
//! up to 7 triangles, never dropped) when they are emitted.
//!
//! Numbers: [`f32`] or [`Fx`] ([`real`](Real) docs), chosen by type, e.g.
//! `Scene<'_, f32>` on a Cortex-M4F and `Scene<'_, Fx>` on an M0.
//! Both are bit-exact across host and targets. Bad numbers are errors
//! naming what went wrong ([`DrawError`]), never silent drops.
//!
//! ```
//! use tilerast::geometry::*;
//! use tilerast::prelude::*;
//!
//! // A one-triangle mesh (normally `include_bytes!` of an exported mesh).
//! let data = MeshData {
//!     center: [0; 3], extent: 1 << 16,
//!     positions: &[[-20000, -20000, 0], [20000, -20000, 0], [0, 20000, 0]],
//!     normals: Some(&[[0, 0, 32767]; 3]), colors: None,
//!     groups: &[Group { first_triangle: 0, triangles: 1, first_vertex: 0, vertices: 3,
//!                       material: Material::diffuse(Rgb::new(255, 120, 0)) }],
//!     triangles: &[[0, 1, 2]],
//! };
//! let mut bytes = [0u8; 96];
//! let n = data.encode(&mut bytes)?;
//! let mesh = Mesh::parse(&bytes[..n])?;
//!
//! let mut slots = [VertexSlot::EMPTY; 16];
//! let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
//! scene.set_camera(
//!     Mat4::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])?,
//!     Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 5.0)?,
//! );
//! scene.set_viewport(Rect::new(0, 0, 64, 64))?;
//! scene.set_lighting(Lighting::white([0.4, 0.6, 1.0], 0.2)?);
//! // Per frame: clear, draw with this frame's rotation, render.
//! scene.clear();
//! let stats = scene.draw(&mesh, &Mat4::rotation_y(Angle::degrees(30)), &DrawOptions::default())?;
//! assert_eq!((stats.vertices, stats.front), (3, 1));
//! let mut tris = 0;
//! scene.each(|c| if matches!(c, Command::Triangle { .. }) { tris += 1 })?;
//! assert_eq!(tris, 1);
//! # Ok::<(), tilerast::Error>(())
//! ```

mod clip;
mod math;
mod mesh;
mod real;

pub use math::{cross, dot, normalize, sub, Mat4, Vec3};
pub use mesh::{Group, Material, Mesh, MeshData, CUBE_BYTES};
pub(crate) use real::isqrt;
pub use real::{Angle, Fx, Real};

use crate::command::{Command, QuadVertex, State, Vertex};
use crate::config::TileConfig;
use crate::error::Error;
use crate::format::Rgb;
use crate::frame::CommandSource;
use crate::geom::{MeshVertex, Rect, SubBox};
use crate::numeric::COORD_LIMIT;
use crate::tile::Tile;
use clip::{ClipVertex, ALL};

/// A box on screen: the pixels geometry inside a world-space box can
/// touch, and a depth no fragment of it is nearer than
/// ([`Scene::screen_box`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScreenBox {
    /// Pixels, inside the viewport.
    pub rect: Rect,
    /// 16-bit depth at or below every fragment's.
    pub z: u16,
}

/// Directional lights a [`Lighting`] holds at most.
pub const MAX_LIGHTS: usize = 4;

/// A directional light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light<S> {
    /// Unit direction *towards* the light, world space.
    pub direction: Vec3<S>,
    /// Intensity per channel, `0..=1` typical.
    pub color: Vec3<S>,
}

/// The scene's lights: an ambient term and up to [`MAX_LIGHTS`]
/// directional lights.
#[derive(Debug, Clone, PartialEq)]
pub struct Lighting<S> {
    /// Ambient intensity per channel (multiplies each material's `ka`).
    pub ambient: Vec3<S>,
    /// Directional lights.
    pub lights: heapless::Vec<Light<S>, MAX_LIGHTS>,
}

impl<S: Real> Lighting<S> {
    /// No light at all: every lit surface is black.
    pub const fn dark() -> Self {
        Lighting {
            ambient: [S::ZERO; 3],
            lights: heapless::Vec::new(),
        }
    }

    /// One white light towards `direction` (normalised here) of intensity
    /// `1 - ambient`, and white ambient light `ambient`: a surface facing
    /// the light shows its full diffuse colour.
    pub fn white(direction: Vec3<S>, ambient: S) -> Result<Self, Error> {
        let mut l = Lighting {
            ambient: [ambient; 3],
            lights: heapless::Vec::new(),
        };
        l.add(direction, [S::ONE - ambient; 3])?;
        Ok(l)
    }

    /// Adds a light towards `direction` (normalised here):
    /// [`Error::ListFull`] past [`MAX_LIGHTS`], [`Error::Degenerate`] for a
    /// zero or non-finite direction.
    pub fn add(&mut self, direction: Vec3<S>, color: Vec3<S>) -> Result<(), Error> {
        let direction = normalize(direction)?;
        self.lights
            .push(Light { direction, color })
            .map_err(|_| Error::ListFull)
    }
}

pub use crate::command::Cull;

/// An opaque Gouraud mesh triangle straight from a [`Scene`]'s vertex
/// cache: three compact vertices and the state to draw them with. The tile
/// draws it as the [`Command::Triangle`] of the same vertices, without the
/// command being built ([`Primitive::Mesh`]).
#[derive(Debug, Clone, Copy)]
pub struct MeshTriangle<'c> {
    pub(crate) v: [&'c MeshVertex; 3],
    pub(crate) state: State,
}

impl MeshTriangle<'_> {
    /// The [`Command::Triangle`] it draws as.
    ///
    /// ```
    /// use tilerast::geometry::*;
    /// use tilerast::prelude::*;
    /// let mut bytes = [0u8; CUBE_BYTES];
    /// let cube = Mesh::cube(&mut bytes)?;
    /// let mut slots = [VertexSlot::EMPTY; 24];
    /// let mut scene: Scene<'_, f32, 1> = Scene::new(&mut slots);
    /// scene.set_camera(Mat4::look_at([2.0, 1.5, 3.0], [0.0; 3], [0.0, 1.0, 0.0])?,
    ///                  Mat4::perspective(Angle::degrees(50), 1.0, 1.0, 20.0)?);
    /// scene.set_viewport(Rect::new(0, 0, 32, 32))?;
    /// scene.draw(&cube, &Mat4::scale([1.0; 3]), &DrawOptions::default())?;
    /// let (mut prims, mut cmds) = (vec![], vec![]);
    /// scene.each_primitive_of(0, |p| prims.push(match p {
    ///     Primitive::Mesh(t) => t.command(),
    ///     Primitive::Command(c) => *c,
    /// }));
    /// scene.each_of(0, |c| cmds.push(*c));
    /// assert_eq!(prims, cmds);
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn command(&self) -> Command {
        Command::Triangle {
            v: self.v.map(|v| v.vertex()),
            state: self.state,
        }
    }

    /// Its pixel bounds: the command's [`Command::bounds`].
    pub(crate) fn bounds(&self) -> Option<Rect> {
        SubBox::of_points(self.v.map(|v| (v.x, v.y))).pixels()
    }

    /// Its nearest vertex depth.
    pub(crate) fn nearest(&self) -> u16 {
        self.v[0].z.min(self.v[1].z).min(self.v[2].z)
    }

    /// Draws it into `tile` ([`Tile::draw`] of [`Self::command`]).
    #[inline(always)]
    pub(crate) fn draw<const N: usize, C: TileConfig>(&self, tile: &mut Tile<N, C>) {
        tile.draw_mesh_triangle(self.v, &self.state);
    }
}

/// One primitive of a draw ([`Scene::each_primitive_of`]): a command, or a
/// mesh triangle that goes to the tile without one.
#[derive(Debug, Clone, Copy)]
pub enum Primitive<'c> {
    /// A command (clipped pieces, Phong, per-triangle flat shading).
    Command(&'c Command),
    /// An unclipped opaque Gouraud triangle from the vertex cache.
    Mesh(MeshTriangle<'c>),
}

/// How a draw's lit triangles are shaded between their vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Shading {
    /// Colours lit at the vertices, interpolated linearly (one addition
    /// per channel and pixel).
    #[default]
    Gouraud,
    /// The RE's fast Phong (seed 001 §IV.2): each triangle also lights the
    /// midpoints of its edges with the normalised mean of the two vertex
    /// normals — exact Phong at six points — and the raster stage steps the
    /// quadratic through the six colours ([`Command::Quadratic`]: two
    /// additions per channel and pixel). Needs normals and a tile
    /// configuration with [`QuadraticShading`](crate::fragment::QuadraticShading);
    /// triangles the geometry stage clips, and meshes without normals, stay
    /// Gouraud.
    ///
    /// **Domain.** The quadratic follows exact Phong closely while a
    /// triangle's normals spread little: within 2 LSB (diffuse) up to
    /// about the spread `reports/phong.md` measures on tessellated spheres;
    /// past it the error grows but stays below Gouraud's. A triangle with
    /// two vertex normals 90° or more apart (a crease: the midpoint normal
    /// means nothing) is drawn Gouraud-shaded.
    FastPhong,
}

/// How one draw is rendered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DrawOptions {
    /// Window ID and plane mask of every triangle; a non-zero object tag
    /// gives group `g` the tag `tag + g` (coverage antialiasing).
    pub state: State,
    /// Face culling.
    pub cull: Cull,
    /// Fronts wind clockwise in model space (default: counter-clockwise,
    /// as OBJ and OpenGL).
    pub clockwise: bool,
    /// Light the vertices (default); otherwise each vertex takes its
    /// diffuse colour.
    pub lit: bool,
    /// Gouraud (default) or fast Phong.
    pub shading: Shading,
}

impl Default for DrawOptions {
    fn default() -> Self {
        DrawOptions {
            state: State::default(),
            cull: Cull::Back,
            clockwise: false,
            lit: true,
            shading: Shading::Gouraud,
        }
    }
}

/// What one draw (or a whole frame, summed) did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DrawStats {
    /// Vertices transformed.
    pub vertices: u32,
    /// Vertices lit (those visible triangles use).
    pub lit: u32,
    /// Triangles inside the guard band and depth range, facing the camera.
    pub front: u32,
    /// Triangles culled by their winding (or degenerate on screen).
    pub culled: u32,
    /// Triangles that cross the near or far plane or the guard band: they
    /// are clipped, not dropped.
    pub clipped: u32,
    /// Triangles wholly outside one plane: invisible.
    pub outside: u32,
    /// Draws skipped whole because their box is outside the view frustum.
    pub meshes_culled: u32,
}

impl DrawStats {
    fn add(&mut self, o: &DrawStats) {
        self.vertices += o.vertices;
        self.lit += o.lit;
        self.front += o.front;
        self.culled += o.culled;
        self.clipped += o.clipped;
        self.outside += o.outside;
        self.meshes_culled += o.meshes_culled;
    }
}

/// Why a draw was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DrawError {
    /// Vertex `vertex` transformed to NaN or infinity (`f32`), or
    /// overflowed the fixed-point range (`Fx`).
    NotFinite {
        /// The vertex's index in its mesh.
        vertex: u16,
    },
    /// The camera, projection or model matrix is not finite, or the
    /// viewport is empty.
    Degenerate,
    /// The vertex cache cannot hold this mesh's vertices.
    CacheFull {
        /// Vertices the mesh has.
        needed: u32,
        /// Entries left.
        free: u32,
    },
    /// The scene's draw list is full.
    TooManyDraws,
}

impl core::fmt::Display for DrawError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DrawError::NotFinite { vertex } => {
                write!(f, "vertex {vertex} is not finite after the transform")
            }
            DrawError::Degenerate => f.write_str("camera, projection or transform is degenerate"),
            DrawError::CacheFull { needed, free } => write!(
                f,
                "vertex cache full: the mesh has {needed} vertices, {free} entries are free"
            ),
            DrawError::TooManyDraws => f.write_str("too many draws in one scene"),
        }
    }
}

impl core::error::Error for DrawError {}

/// `?` in a helper that renders: a refused draw is the raster core's error.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::geometry::DrawError;
/// fn frame() -> Result<(), FlushError<()>> {
///     Err(DrawError::Degenerate)?
/// }
/// assert_eq!(frame(), Err(FlushError::Raster(Error::Degenerate)));
/// ```
impl<E> From<DrawError> for crate::error::FlushError<E> {
    fn from(e: DrawError) -> Self {
        crate::error::FlushError::Raster(e.into())
    }
}

impl From<DrawError> for Error {
    fn from(e: DrawError) -> Self {
        match e {
            DrawError::NotFinite { .. } => Error::NotFinite,
            DrawError::Degenerate => Error::Degenerate,
            DrawError::CacheFull { .. } | DrawError::TooManyDraws => Error::ListFull,
        }
    }
}

/// One slot of the vertex cache: a vertex after the vertex stage, 16
/// bytes. The application lends the scene an array of them
/// ([`Scene::new`]); its contents are private.
#[derive(Debug, Clone, Copy, Default)]
pub struct VertexSlot {
    /// Sub-pixel position (valid when `code & ALL == 0`), depth, lit
    /// colour, and in `code` the outcode bits ([`clip`]; bit 7: a visible
    /// triangle uses it): what the tile's mesh path reads in place.
    v: MeshVertex,
}

const USED: u8 = 0x80;

impl VertexSlot {
    /// An empty slot, to initialise the array.
    pub const EMPTY: VertexSlot = VertexSlot {
        v: MeshVertex {
            x: 0,
            y: 0,
            z: 0,
            rgb: [0; 3],
            code: 0,
            spare: 0,
        },
    };
    fn vertex(&self) -> Vertex {
        self.v.vertex()
    }
}

/// The viewport in the back end's numbers.
#[derive(Debug, Clone, Copy, Default)]
struct View<S> {
    /// Centre and half-size, pixels.
    cx: S,
    cy: S,
    hw: S,
    hh: S,
    /// Guard band half-size in `w` units per axis.
    guard: [S; 2],
}

impl<S: Real> View<S> {
    /// The viewport rectangle in pixels.
    fn rect(&self) -> Rect {
        let (x2, y2) = (
            self.cx.to_fixed(1).unwrap_or(0),
            self.cy.to_fixed(1).unwrap_or(0),
        );
        let (w, h) = (
            self.hw.to_fixed(1).unwrap_or(0),
            self.hh.to_fixed(1).unwrap_or(0),
        );
        Rect::new((x2 - w) / 2, (y2 - h) / 2, w.max(0) as u32, h.max(0) as u32)
    }

    /// Projects an inside clip-space point to sub-pixels and depth.
    #[inline]
    fn project(&self, p: &[S; 4]) -> Option<(i32, i32, u16)> {
        let iw = S::ONE.div(p[3]);
        let x = self.cx + p[0] * iw * self.hw;
        let y = self.cy - p[1] * iw * self.hh;
        // round(z * 65535), as one rounding of z * 65535 / 65536 to 16
        // fraction bits (the factor is exact in both back ends, and
        // z * 65535 itself would not fit `Fx`).
        let z = (p[2] * iw).max(S::ZERO).min(S::ONE) * S::from_q(65535, 16);
        let z = z.round_small(16)?.clamp(0, 65535) as u16;
        Some((x.round_small(4)?, y.round_small(4)?, z))
    }
}

/// A light turned into one draw's model space.
#[derive(Debug, Clone, Copy, Default)]
struct ModelLight<S> {
    dir: Vec3<S>,
    half: Vec3<S>,
    color: Vec3<S>,
}

#[derive(Debug, Clone)]
struct Draw<'m, S> {
    mesh: Mesh<'m>,
    /// Projection * view * model * dequantisation.
    mvp: Mat4<S>,
    /// First cache entry.
    first: u32,
    /// First triangle key (key = triangle << 3 | piece).
    tri_base: u32,
    opts: DrawOptions,
    /// The lights in model space, kept for fast Phong's midpoints.
    lights: heapless::Vec<ModelLight<S>, MAX_LIGHTS>,
    /// Whether the spare bits of the draw's cache slots list its drawn
    /// triangles (bit `t % 16` of slot `t / 16`): every triangle is then
    /// inside the guard band or wholly outside, and binning visits the
    /// front ones without reading or culling the others (the M4 teapot:
    /// half its triangles are back faces).
    front_bits: bool,
    /// Where [`Scene::keep_clipped`] stored the draw's clipped pieces:
    /// first slot and number of pieces (three slots each).
    pieces: Option<(u32, u32)>,
}

/// A frame's 3D scene: camera, viewport, lights, up to `D` draws of
/// meshes, and the vertex cache they share — slots the application lends
/// (16 bytes each: a `static` array on a device, a `Vec` on the host). A
/// [`CommandSource`] for [`Frame`](crate::frame::Frame)s.
///
/// The teapot (3,644 vertices) needs 3,644 slots, 58 KB; a cube with face
/// normals 24 slots, 384 bytes.
///
/// ```
/// use tilerast::geometry::{Scene, VertexSlot};
/// let mut slots = [VertexSlot::EMPTY; 24];
/// let scene: Scene<'_, f32> = Scene::new(&mut slots);
/// assert_eq!(scene.capacity(), 24);
/// assert_eq!(core::mem::size_of::<VertexSlot>(), 16);
/// ```
pub struct Scene<'a, S: Real, const D: usize = 4> {
    view: Mat4<S>,
    proj: Mat4<S>,
    viewport: View<S>,
    lighting: Lighting<S>,
    cache: &'a mut [VertexSlot],
    used: usize,
    draws: heapless::Vec<Draw<'a, S>, D>,
    stats: DrawStats,
}

impl<'a, S: Real, const D: usize> Scene<'a, S, D> {
    /// An empty scene over the vertex cache `slots`: identity camera and
    /// projection, no viewport, no light.
    pub fn new(slots: &'a mut [VertexSlot]) -> Self {
        Scene {
            view: Mat4::IDENTITY,
            proj: Mat4::IDENTITY,
            viewport: View::default(),
            lighting: Lighting::dark(),
            cache: slots,
            used: 0,
            draws: heapless::Vec::new(),
            stats: DrawStats::default(),
        }
    }

    /// Vertex cache slots.
    pub fn capacity(&self) -> usize {
        self.cache.len()
    }

    /// Sets the view (world to camera) and projection matrices. Draws made
    /// before keep the camera they were made with.
    pub fn set_camera(&mut self, view: Mat4<S>, projection: Mat4<S>) {
        self.view = view;
        self.proj = projection;
    }

    /// Sets the screen rectangle normalised device coordinates map to
    /// (`y` up on screen in NDC, down in pixels). [`Error::Degenerate`] for
    /// an empty one or one beyond the coordinate domain.
    pub fn set_viewport(&mut self, r: Rect) -> Result<(), Error> {
        let lim = COORD_LIMIT as i64;
        let ok = r.w > 0
            && r.h > 0
            && r.w <= 4096
            && r.h <= 4096
            && (r.x as i64).abs() < lim / 2
            && (r.y as i64).abs() < lim / 2;
        if !ok {
            return Err(Error::Degenerate);
        }
        // Twice the centre, in pixels (exact), then halved.
        let (cx2, cy2) = (2 * r.x + r.w as i32, 2 * r.y + r.h as i32);
        let (hw, hh) = (S::from_q(r.w as i64, 1), S::from_q(r.h as i64, 1));
        // Guard band: |centre| + g * half-size stays 64 px inside the
        // coordinate limit.
        let room = |c2: i32| S::from_i32(COORD_LIMIT - 64 - (c2.abs() + 1) / 2);
        self.viewport = View {
            cx: S::from_q(cx2 as i64, 1),
            cy: S::from_q(cy2 as i64, 1),
            hw,
            hh,
            guard: [room(cx2).div(hw), room(cy2).div(hh)],
        };
        Ok(())
    }

    /// Sets the lights used by later draws.
    pub fn set_lighting(&mut self, lighting: Lighting<S>) {
        self.lighting = lighting;
    }

    /// Forgets every draw (the start of a frame).
    pub fn clear(&mut self) {
        self.used = 0;
        self.draws.clear();
        self.stats = DrawStats::default();
    }

    /// What the draws since [`clear`](Self::clear) did, summed.
    pub fn stats(&self) -> DrawStats {
        self.stats
    }

    /// Draws `mesh` placed by `model`: runs the vertex stage now ([module
    /// docs](self)) and keeps the mesh's triangles for the frame.
    pub fn draw(
        &mut self,
        mesh: &Mesh<'a>,
        model: &Mat4<S>,
        opts: &DrawOptions,
    ) -> Result<DrawStats, DrawError> {
        let nv = mesh.vertices() as usize;
        if self.draws.is_full() {
            return Err(DrawError::TooManyDraws);
        }
        let free = self.cache.len() - self.used;
        if free < nv {
            return Err(DrawError::CacheFull {
                needed: nv as u32,
                free: free as u32,
            });
        }
        if !real::above(self.viewport.hw, S::ZERO) {
            return Err(DrawError::Degenerate);
        }
        let c = mesh.center().map(|c| S::from_q(c as i64, 16));
        let e = S::from_q(mesh.extent() as i64, 16);
        let dequant = Mat4::translation(c).mul(&Mat4::scale([e; 3]));
        let mvp = self.proj.mul(&self.view).mul(&model.mul(&dequant));
        if !mvp.is_finite() || !model.is_finite() {
            return Err(DrawError::Degenerate);
        }
        let mut stats = DrawStats::default();

        // 1. The box [-1, 1]^3 (quantised units) against the frustum.
        let one = [S::ONE; 2];
        let mut all = ALL;
        for k in 0..8 {
            let s = |bit: u32| if k & bit != 0 { S::ONE } else { -S::ONE };
            all &= clip::outcode(&mvp.transform([s(1), s(2), s(4)]), one);
        }
        if all != 0 {
            stats.meshes_culled = 1;
            self.stats.add(&stats);
            return Ok(stats);
        }

        // 2. Transform and project every vertex into the cache. When no
        // position can overflow (the rows' absolute sums are small, checked
        // once), the per-vertex finiteness test is skipped; when the whole
        // box lies inside the guard band and depth range
        // ([`clip::box_inside`]), so does every vertex and its outcode is
        // not computed (the same numbers: 0).
        let mvp = q15_matrix(&mvp);
        let bounded = bounded(&mvp);
        let first = self.used;
        let vp = self.viewport;
        let cache = &mut self.cache[first..first + nv];
        let inside = bounded
            && clip::box_inside(&mvp.m, vp.guard)
            && project_all::<S, true>(mesh, &mvp, true, &vp, cache)?;
        if !inside {
            project_all::<S, false>(mesh, &mvp, bounded, &vp, cache)?;
        }
        stats.vertices = nv as u32;

        // 3. Cull and mark the vertices visible triangles use; note the
        // front triangles in the cache's spare bits (16 a slot) when they
        // fit, so binning walks only them ([`Draw::front_bits`]).
        let bits = mesh.triangles() as usize <= 16 * nv;
        if inside {
            mark_used::<true>(mesh, cache, opts, bits, &mut stats);
        } else {
            mark_used::<false>(mesh, cache, opts, bits, &mut stats);
        }

        // 4. Light the marked vertices, group by group, in model space.
        let lights = model_lights(&self.lighting, model, &self.view);
        let ambient = &self.lighting.ambient;
        for g in 0..mesh.groups() {
            let grp = mesh.group(g);
            let m = grp.material;
            // The group's shading, unless each vertex has its own colour.
            let shared = Lit::new(m.kd, m.ka, &m, ambient);
            for i in grp.first_vertex..grp.first_vertex + grp.vertices {
                let slot = &mut cache[i as usize];
                if slot.v.code & USED == 0 {
                    continue;
                }
                stats.lit += 1;
                let color = mesh.color(i);
                let kd = color.unwrap_or(m.kd);
                slot.v.rgb = match mesh.normal(i).filter(|_| opts.lit) {
                    Some(n) => {
                        let n = n.map(|c| S::from_q(c as i64, 15));
                        match color {
                            Some(c) => Lit::new(c, c, &m, ambient).at(n, &lights),
                            None => shared.at(n, &lights),
                        }
                    }
                    None => [kd.r, kd.g, kd.b],
                };
            }
        }

        self.used += nv;
        let tri_base = self
            .draws
            .last()
            .map_or(0, |d: &Draw<'a, S>| d.tri_base + d.mesh.triangles() as u32);
        // Checked above: not full.
        let _ = self.draws.push(Draw {
            mesh: *mesh,
            mvp,
            first: first as u32,
            tri_base,
            opts: *opts,
            lights,
            front_bits: bits && stats.clipped == 0,
            pieces: None,
        });
        self.stats.add(&stats);
        Ok(stats)
    }

    /// Draws made since [`clear`](Self::clear) (a mesh wholly outside the
    /// frustum makes none).
    pub fn draw_count(&self) -> usize {
        self.draws.len()
    }

    /// Calls `f` with every command of draw `draw` (in draw order since
    /// [`clear`](Self::clear)): what replaying that draw's keys gives, for
    /// a caller that keeps draws apart ([`crate::occlusion`]).
    pub fn each_of(&self, draw: usize, mut f: impl FnMut(&Command)) {
        let Some(d) = self.draws.get(draw) else {
            return;
        };
        for t in 0..d.mesh.triangles() {
            self.emit(d, t, |_| true, &mut |_, c: &Command| f(c));
        }
    }

    /// Clips draw `draw`'s clipped triangles once and keeps their pieces in
    /// the vertex cache's free slots (three a piece), so that
    /// [`each_primitive_of`](Self::each_primitive_of) hands them over as
    /// [`Primitive::Mesh`] instead of clipping them again each time it is
    /// called — the culling walk asks once per tile an object touches.
    /// Returns whether they are kept: not for a draw whose triangles go as
    /// commands (fast Phong), nor when the free slots are too few (then
    /// nothing changes).
    ///
    /// ```
    /// use tilerast::geometry::*;
    /// use tilerast::prelude::*;
    /// let mut bytes = [0u8; CUBE_BYTES];
    /// let cube = Mesh::cube(&mut bytes)?;
    /// let mut slots = [VertexSlot::EMPTY; 128];
    /// let mut scene: Scene<'_, f32, 1> = Scene::new(&mut slots);
    /// // The near plane cuts the cube's nearest corner off.
    /// scene.set_camera(Mat4::look_at([1.5, 1.2, 2.5], [0.0; 3], [0.0, 1.0, 0.0])?,
    ///                  Mat4::perspective(Angle::degrees(70), 1.0, 3.0, 20.0)?);
    /// scene.set_viewport(Rect::new(0, 0, 32, 32))?;
    /// let st = scene.draw(&cube, &Mat4::scale([1.0; 3]), &DrawOptions::default())?;
    /// assert!(st.clipped > 0);
    /// let all = |scene: &Scene<'_, f32, 1>| {
    ///     let mut out = vec![];
    ///     scene.each_primitive_of(0, |p| out.push(match p {
    ///         Primitive::Mesh(t) => t.command(),
    ///         Primitive::Command(c) => *c,
    ///     }));
    ///     out
    /// };
    /// let meshes = |scene: &Scene<'_, f32, 1>| {
    ///     let mut n = 0;
    ///     scene.each_primitive_of(0, |p| n += matches!(p, Primitive::Mesh(_)) as u32);
    ///     n
    /// };
    /// let (before, m) = (all(&scene), meshes(&scene));
    /// assert!(scene.keep_clipped(0));
    /// assert_eq!(all(&scene), before); // the same triangles, in the same order
    /// assert!(meshes(&scene) > m); // the clipped pieces now come from the cache
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn keep_clipped(&mut self, draw: usize) -> bool {
        let Some(d) = self.draws.get(draw) else {
            return false;
        };
        if d.pieces.is_some() {
            return true;
        }
        if d.opts.shading != Shading::Gouraud && d.opts.lit {
            return false;
        }
        let base = d.first as usize;
        let mut at = self.used;
        let mut pieces = 0u32;
        for t in 0..d.mesh.triangles() {
            let v = d.mesh.triangle(t).map(|i| &self.cache[base + i as usize]);
            let (or, and) = (
                v[0].v.code | v[1].v.code | v[2].v.code,
                v[0].v.code & v[1].v.code & v[2].v.code,
            );
            if or & ALL == 0 || and & ALL != 0 {
                continue;
            }
            // At most 7 pieces (a 9-gon's fan).
            let mut kept: heapless::Vec<[MeshVertex; 3], 7> = heapless::Vec::new();
            self.emit(d, t, |_| true, &mut |_, c: &Command| {
                if let Command::Triangle { v, .. } = c {
                    let _ = kept.push(v.each_ref().map(MeshVertex::of));
                }
            });
            if at + 3 * kept.len() > self.cache.len() {
                return false;
            }
            for piece in kept {
                for mut v in piece {
                    // The piece's triangle, for `each_primitive_of`'s order.
                    v.spare = t;
                    self.cache[at] = VertexSlot { v };
                    at += 1;
                }
                pieces += 1;
            }
        }
        let first = self.used as u32;
        self.used = at;
        self.draws[draw].pieces = Some((first, pieces));
        true
    }

    /// Calls `f` with every primitive of draw `draw`: what
    /// [`each_of`](Self::each_of) gives, with each unclipped Gouraud
    /// triangle as a [`Primitive::Mesh`] read in place from the vertex
    /// cache instead of a command (the culling walk's fused path:
    /// [`crate::occlusion`]).
    pub fn each_primitive_of(&self, draw: usize, mut f: impl FnMut(Primitive<'_>)) {
        let Some(d) = self.draws.get(draw) else {
            return;
        };
        // As `draw_keys`: a draw's Gouraud triangles go straight to the tile.
        let direct = !(d.opts.shading != Shading::Gouraud && d.opts.lit);
        let base = &self.cache[d.first as usize..];
        let shared = d.opts.state.tag == 0 || d.mesh.groups() == 1;
        let state = |t: u16| {
            if shared {
                d.opts.state
            } else {
                tagged(&d.mesh, &d.opts.state, t)
            }
        };
        if direct && d.front_bits {
            // No triangle clipped: the drawn ones are the front bits, in
            // triangle order, none read or culled again (the culling walk
            // asks once per tile an object touches).
            each_front(d, base, |t| {
                let v = d.mesh.triangle(t).map(|i| &base[i as usize].v);
                f(Primitive::Mesh(MeshTriangle { v, state: state(t) }));
            });
            return;
        }
        let sign = front_sign(&d.opts);
        // The kept pieces of clipped triangles, in triangle order.
        let mut pieces = match d.pieces {
            Some((first, n)) => {
                self.cache[first as usize..(first + 3 * n) as usize].chunks_exact(3)
            }
            None => [].chunks_exact(3),
        };
        let mut next = pieces.next();
        for t in 0..d.mesh.triangles() {
            if direct {
                let v = d.mesh.triangle(t).map(|i| &base[i as usize]);
                let (or, and) = (
                    v[0].v.code | v[1].v.code | v[2].v.code,
                    v[0].v.code & v[1].v.code & v[2].v.code,
                );
                if (or | and) & ALL == 0 {
                    if faces(area(&v), d.opts.cull, sign) {
                        f(Primitive::Mesh(MeshTriangle {
                            v: v.map(|s| &s.v),
                            state: state(t),
                        }));
                    }
                    continue;
                }
                if d.pieces.is_some() {
                    while let Some(p) = next.filter(|p| p[0].v.spare == t) {
                        f(Primitive::Mesh(MeshTriangle {
                            v: [&p[0].v, &p[1].v, &p[2].v],
                            state: state(t),
                        }));
                        next = pieces.next();
                    }
                    continue;
                }
            }
            self.emit(d, t, |_| true, &mut |_, c: &Command| {
                f(Primitive::Command(c))
            });
        }
    }

    /// The screen rectangle and nearest depth of the world-space box
    /// `lo..=hi` under this scene's camera and viewport, widened so that
    /// every fragment of geometry inside the box lies in the rectangle and
    /// is no nearer than `z` ([`ScreenBox`]). A box reaching behind the
    /// camera (a corner with `w` at or below `near`'s side) covers the
    /// viewport at depth 0; `None` when the box lies wholly outside one
    /// frustum plane (nothing inside it can be drawn).
    ///
    /// ```
    /// use tilerast::geometry::*;
    /// use tilerast::prelude::*;
    /// let mut slots = [VertexSlot::EMPTY; 1];
    /// let mut scene: Scene<'_, f32> = Scene::new(&mut slots);
    /// scene.set_camera(
    ///     Mat4::look_at([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0])?,
    ///     Mat4::perspective(Angle::degrees(60), 1.0, 1.0, 10.0)?,
    /// );
    /// scene.set_viewport(Rect::new(0, 0, 64, 64))?;
    /// let b = scene.screen_box([-0.5; 3], [0.5; 3]).unwrap();
    /// assert!(b.rect.x > 16 && b.rect.x1() < 48 && b.z > 0);
    /// assert!(scene.screen_box([20.0; 3], [21.0; 3]).is_none()); // off screen
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn screen_box(&self, lo: Vec3<S>, hi: Vec3<S>) -> Option<ScreenBox> {
        let vp = self.viewport;
        let full = ScreenBox {
            rect: vp.rect(),
            z: 0,
        };
        let pv = self.proj.mul(&self.view);
        let mut all = ALL;
        let mut corners = [[S::ZERO; 4]; 8];
        for (k, c) in corners.iter_mut().enumerate() {
            let pick = |a: usize, bit: usize| if k & bit != 0 { hi[a] } else { lo[a] };
            *c = pv.transform([pick(0, 1), pick(1, 2), pick(2, 4)]);
            if !c.iter().all(|v| v.is_finite()) {
                return Some(full);
            }
            all &= clip::outcode(c, [S::ONE; 2]);
        }
        if all != 0 {
            return None;
        }
        // A corner at or behind the near plane has no screen position.
        if corners
            .iter()
            .any(|c| c[2] < S::ZERO || !real::above(c[3], S::ZERO))
        {
            return Some(full);
        }
        let (mut x0, mut y0, mut x1, mut y1, mut z) =
            (i32::MAX, i32::MAX, i32::MIN, i32::MIN, u16::MAX);
        for c in &corners {
            let Some((x, y, cz)) = vp.project(c) else {
                return Some(full);
            };
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            z = z.min(cz);
        }
        // Sub-pixels to pixels, one pixel of margin for the vertices'
        // own rounding; two depth units below the nearest corner.
        let px = |v: i32| (v >> 4) as i64;
        let r = Rect::new(
            (px(x0) - 1) as i32,
            (px(y0) - 1) as i32,
            (px(x1) - px(x0) + 3) as u32,
            (px(y1) - px(y0) + 3) as u32,
        );
        Some(ScreenBox {
            rect: r.intersect(&vp.rect())?,
            z: z.saturating_sub(2),
        })
    }

    /// The projected vertex `i` of draw `draw` (in draw order since
    /// [`clear`](Self::clear)), if it lies inside the depth range and guard
    /// band; its colour is lit only if a visible triangle uses it.
    pub fn projected(&self, draw: usize, i: u16) -> Option<Vertex> {
        let d = self.draws.get(draw)?;
        if i >= d.mesh.vertices() {
            return None;
        }
        let c = self.cache.get(d.first as usize + i as usize)?;
        (c.v.code & ALL == 0).then(|| c.vertex())
    }

    /// Calls `f(key, command)` for the pieces of triangle `t` of draw `d`
    /// whose piece number passes `want`.
    fn emit(
        &self,
        d: &Draw<'a, S>,
        t: u16,
        want: impl Fn(u32) -> bool,
        f: &mut impl FnMut(u32, &Command),
    ) {
        let mesh = &d.mesh;
        let idx = mesh.triangle(t);
        let base = &self.cache[d.first as usize..];
        let v = idx.map(|i| &base[i as usize]);
        let or = (v[0].v.code | v[1].v.code | v[2].v.code) & ALL;
        let and = v[0].v.code & v[1].v.code & v[2].v.code & ALL;
        let key = (d.tri_base + t as u32) << 3;
        let state = tagged(mesh, &d.opts.state, t);
        let sign = front_sign(&d.opts);
        if and != 0 {
            return;
        }
        if or == 0 {
            if want(0) && faces(area(&v), d.opts.cull, sign) {
                let vs = v.map(|c| c.vertex());
                let cmd = match self.midpoints(d, t, &idx) {
                    Some(mid) => Command::Quadratic {
                        alpha: 255,
                        v: [0, 1, 2].map(|k| QuadVertex::new(vs[k], mid[k])),
                        state,
                    },
                    None => Command::Triangle { v: vs, state },
                };
                f(key, &cmd);
            }
            return;
        }
        // Clip in homogeneous space, then fan.
        let tri = core::array::from_fn(|k| ClipVertex {
            p: clip_position(mesh, &d.mvp, idx[k]),
            c: v[k].v.rgb.map(|c| S::from_i32(c as i32)),
        });
        let poly = clip::clip(tri, or, self.viewport.guard);
        let poly = poly.vertices();
        if poly.len() < 3 {
            return;
        }
        let proj = |cv: &ClipVertex<S>| -> Option<VertexSlot> {
            let (x, y, z) = self.viewport.project(&cv.p)?;
            let rgb = cv.c.map(|c| c.to_fixed(0).unwrap_or(0).clamp(0, 255) as u8);
            Some(VertexSlot {
                v: MeshVertex {
                    x,
                    y,
                    z,
                    rgb,
                    code: 0,
                    spare: 0,
                },
            })
        };
        let Some(a) = proj(&poly[0]) else { return };
        for piece in 1..poly.len() - 1 {
            if !want(piece as u32 - 1) {
                continue;
            }
            let (Some(b), Some(c)) = (proj(&poly[piece]), proj(&poly[piece + 1])) else {
                continue;
            };
            let tri = [&a, &b, &c];
            if !faces(area(&tri), d.opts.cull, sign) {
                continue;
            }
            let cmd = Command::Triangle {
                v: tri.map(|c| c.vertex()),
                state,
            };
            if cmd.validate().is_ok() {
                f(key | (piece as u32 - 1), &cmd);
            }
        }
    }
}

impl<'a, S: Real, const D: usize> Scene<'a, S, D> {
    /// Fast Phong's edge-midpoint colours of triangle `t` (vertices `idx`):
    /// each lit with the normalised sum of its edge's two vertex normals
    /// and the mean of their colours, exactly as a vertex is lit. `None`
    /// when the draw is Gouraud, unlit or has no normals, or two normals of
    /// an edge are 90° or more apart.
    fn midpoints(&self, d: &Draw<'a, S>, t: u16, idx: &[u16; 3]) -> Option<[Rgb; 3]> {
        if d.opts.shading != Shading::FastPhong || !d.opts.lit {
            return None;
        }
        let mesh = &d.mesh;
        let m = mesh.group(group_of(mesh, t)).material;
        let n = [
            mesh.normal(idx[0])?,
            mesh.normal(idx[1])?,
            mesh.normal(idx[2])?,
        ];
        // Normals 90° or more apart along an edge are a crease, not a
        // smooth surface: no midpoint normal to speak of. (In `i64`: three
        // products of Q15 components reach 3 x 2^30, past `i32` for the
        // unnormalised normals a file may hold — found by the `mesh` fuzz
        // target.)
        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
            let dot: i64 = (0..3).map(|c| n[a][c] as i64 * n[b][c] as i64).sum();
            if dot <= 0 {
                return None;
            }
        }
        let mut out = [Rgb::new(0, 0, 0); 3];
        for (k, o) in out.iter_mut().enumerate() {
            let (a, b) = (k, (k + 1) % 3);
            let sum = core::array::from_fn(|c| S::from_q(n[a][c] as i64 + n[b][c] as i64, 15));
            let nm = normalize(sum).ok()?;
            let mean = |x: Rgb, y: Rgb| {
                let h = |p: u8, q: u8| (p as u16 + q as u16).div_ceil(2) as u8;
                Rgb::new(h(x.r, y.r), h(x.g, y.g), h(x.b, y.b))
            };
            let (kd, ka) = match (mesh.color(idx[a]), mesh.color(idx[b])) {
                (Some(x), Some(y)) => (mean(x, y), mean(x, y)),
                _ => (m.kd, m.ka),
            };
            let c = shade_vec(nm, kd, ka, &m, &d.lights, &self.lighting.ambient);
            *o = Rgb::new(c[0], c[1], c[2]);
        }
        Some(out)
    }
}

/// The group triangle `t` belongs to.
fn group_of(mesh: &Mesh<'_>, t: u16) -> u16 {
    (0..mesh.groups())
        .find(|&g| {
            let grp = mesh.group(g);
            t < grp.first_triangle + grp.triangles
        })
        .unwrap_or(0)
}

/// The clip-space position of vertex `i` through `m`, the draw's matrix
/// as [`q15_matrix`] prepares it.
#[inline]
fn clip_position<S: Real>(mesh: &Mesh<'_>, m: &Mat4<S>, i: u16) -> [S; 4] {
    let q = mesh.position(i);
    m.m.map(|row| S::affine_q15(&row, q, false))
}

/// `mvp` with the `2^-15` of Q15 positions folded into its first three
/// columns when the back end does so ([`Real::FOLD_Q15`]: exact, a power
/// of two), so [`clip_position`] gives the same numbers as scaling each
/// position.
fn q15_matrix<S: Real>(mvp: &Mat4<S>) -> Mat4<S> {
    let mut m = *mvp;
    if S::FOLD_Q15 {
        let s = S::from_q(1, 15);
        for row in &mut m.m {
            for v in &mut row[..3] {
                *v = *v * s;
            }
        }
    }
    m
}

/// Whether no vertex of a mesh can reach a non-finite clip position
/// through `m` ([`q15_matrix`]'s form): each row's sum of absolute values
/// over the largest position (`|q| <= 1`, or `2^15` folded) stays below
/// 2^14, so no product or partial sum can overflow or saturate (either
/// back end: they only grow toward that sum, rounding aside, far below
/// the limit).
fn bounded<S: Real>(m: &Mat4<S>) -> bool {
    let q = S::from_q15(i16::MAX).max(-S::from_q15(i16::MIN));
    let abs = |v: S| v.max(-v);
    let lim = S::from_i32(1 << 14);
    m.m.iter().all(|r| {
        let sum = (abs(r[0]) + abs(r[1]) + abs(r[2])) * q + abs(r[3]);
        sum.is_finite() && sum < lim
    })
}

/// Step 2 of [`Scene::draw`]: every vertex of `mesh` through `mvp`
/// ([`q15_matrix`]'s form) into `cache`, with its outcode and, when
/// inside, its projection. `INSIDE`: the caller found the mesh's box
/// inside ([`clip::box_inside`]), so every outcode is 0 and none is
/// computed; `Ok(false)` then when a projection failed all the same (a
/// degenerate `w`), and the caller runs the general form.
#[inline(always)]
fn project_all<S: Real, const INSIDE: bool>(
    mesh: &Mesh<'_>,
    mvp: &Mat4<S>,
    bounded: bool,
    vp: &View<S>,
    cache: &mut [VertexSlot],
) -> Result<bool, DrawError> {
    for (i, slot) in cache.iter_mut().enumerate() {
        let q = mesh.position(i as u16);
        let p = mvp.m.map(|row| S::affine_q15(&row, q, bounded));
        if !bounded && !p.iter().all(|v| v.is_finite()) {
            return Err(DrawError::NotFinite { vertex: i as u16 });
        }
        let code = if INSIDE {
            0
        } else {
            clip::outcode(&p, vp.guard)
        };
        // Built whole, stored once.
        let mut v = VertexSlot::EMPTY.v;
        v.code = code;
        if code == 0 {
            match vp.project(&p) {
                Some((x, y, z)) => (v.x, v.y, v.z) = (x, y, z),
                // Inside the guard band yet not representable: only a
                // w next to 0, i.e. a degenerate projection.
                None if INSIDE => return Ok(false),
                None => v.code = ALL,
            }
        }
        slot.v = v;
    }
    Ok(true)
}

/// Step 3 of [`Scene::draw`]: culls `mesh`'s triangles against the
/// projected `cache`, marks the vertices of the drawn ones [`USED`], counts
/// them in `stats` and, with `bits`, notes the front ones in the slots'
/// spare bits. `INSIDE`: every vertex's outcode is 0 ([`project_all`]),
/// so no triangle is outside or clipped and none is tested.
#[inline(always)]
fn mark_used<const INSIDE: bool>(
    mesh: &Mesh<'_>,
    cache: &mut [VertexSlot],
    opts: &DrawOptions,
    bits: bool,
    stats: &mut DrawStats,
) {
    let front_sign = front_sign(opts);
    // Counted in locals (registers), added once; the culled ones are the
    // rest.
    let (mut outside, mut front, mut clipped) = (0, 0, 0);
    let mut word = 0u16;
    for (t, idx) in mesh.triangle_list().enumerate() {
        let v = idx.map(|i| &cache[i as usize]);
        let (or, and) = if INSIDE {
            (0, 0)
        } else {
            (
                v[0].v.code | v[1].v.code | v[2].v.code,
                v[0].v.code & v[1].v.code & v[2].v.code,
            )
        };
        let used = if and & ALL != 0 {
            outside += 1;
            false
        } else if or & ALL == 0 {
            let drawn = faces(area(&v), opts.cull, front_sign);
            if drawn {
                front += 1;
                word |= 1 << (t % 16);
            }
            drawn
        } else {
            clipped += 1;
            true
        };
        if used {
            for i in idx {
                // (Inside, every code is 0 or `USED` already: a store.)
                let c = &mut cache[i as usize].v.code;
                *c = if INSIDE { USED } else { *c | USED };
            }
        }
        if t % 16 == 15 {
            if bits {
                cache[t / 16].v.spare = word;
            }
            word = 0;
        }
    }
    let nt = mesh.triangles() as usize;
    if bits && nt % 16 != 0 {
        cache[nt / 16].v.spare = word;
    }
    stats.outside += outside;
    stats.culled += mesh.triangles() as u32 - outside - front - clipped;
    stats.front += front;
    stats.clipped += clipped;
}

/// Calls `f(t)` for each triangle `t` of draw `d` that its front bits
/// list ([`Draw::front_bits`], in the spare bits of its cache slots
/// `base`), in increasing order: its drawn triangles, none read or culled.
#[inline(always)]
fn each_front<S>(d: &Draw<'_, S>, base: &[VertexSlot], mut f: impl FnMut(u16)) {
    let words = (d.mesh.triangles() as usize).div_ceil(16);
    for (w, slot) in base[..words].iter().enumerate() {
        let mut m = slot.v.spare;
        while m != 0 {
            f((w * 16) as u16 + m.trailing_zeros() as u16);
            m &= m - 1;
        }
    }
}

/// Twice the signed screen area (y down), sub-pixels squared.
#[inline]
fn area(v: &[&VertexSlot; 3]) -> i64 {
    // Projected coordinates lie in the guard band (below 2^17 sub-pixels):
    // differences fit `i32`, products are two 32x32-bit multiplies — on
    // the Cortex-M0 four 32-bit ones of 16-bit halves when the second
    // factors are below 2^15 (`dot2_i16`: a mesh's triangles), not two
    // library calls (twice a triangle a frame: the ARMv6-M teapot's vertex
    // stage 5.94 -> 5.58 M instructions a frame, measured).
    let (x0, y0) = (v[0].v.x, v[0].v.y);
    let (dx1, dy1, dx2, dy2) = (v[1].v.x - x0, v[1].v.y - y0, v[2].v.x - x0, v[2].v.y - y0);
    if crate::numeric::LONG_MUL {
        dx1 as i64 * dy2 as i64 - dy1 as i64 * dx2 as i64
    } else {
        crate::numeric::dot2_i16(dx1, dy2, -dy1, dx2)
    }
}

/// The sign of [`area`] for a front face: counter-clockwise fronts (seen
/// with y up) wind clockwise on the y-down screen, a negative area.
fn front_sign(o: &DrawOptions) -> i64 {
    if o.clockwise {
        1
    } else {
        -1
    }
}

/// Whether a triangle of signed area `a` is drawn under `cull`.
#[inline]
fn faces(a: i64, cull: Cull, front: i64) -> bool {
    a != 0
        && match cull {
            Cull::None => true,
            Cull::Back => a.signum() == front,
            Cull::Front => a.signum() != front,
        }
}

/// The state of triangle `t`: group `g`'s tag is `tag + g` when tagged.
fn tagged(mesh: &Mesh<'_>, state: &State, t: u16) -> State {
    if state.tag == 0 || mesh.groups() == 1 {
        return *state;
    }
    let g = group_of(mesh, t);
    State {
        tag: state.tag.wrapping_add(g),
        ..*state
    }
}

/// The lights in model space (for a rotation and uniform scale the
/// transposed 3x3 is the inverse up to scale), with Blinn's half vectors
/// for a viewer at infinity along the camera's axis.
fn model_lights<S: Real>(
    l: &Lighting<S>,
    model: &Mat4<S>,
    view: &Mat4<S>,
) -> heapless::Vec<ModelLight<S>, MAX_LIGHTS> {
    // Towards the camera, world space: the view matrix's third row.
    let eye = [view.m[2][0], view.m[2][1], view.m[2][2]];
    let mut out = heapless::Vec::new();
    for light in &l.lights {
        let dir = normalize(model.transform_dir_transposed(light.direction));
        let h = [
            light.direction[0] + eye[0],
            light.direction[1] + eye[1],
            light.direction[2] + eye[2],
        ];
        let half = normalize(model.transform_dir_transposed(h));
        if let (Ok(dir), Ok(half)) = (dir, half) {
            let _ = out.push(ModelLight {
                dir,
                half,
                color: light.color,
            });
        } else if let Ok(dir) = dir {
            // Light exactly opposite the viewer: no highlight.
            let _ = out.push(ModelLight {
                dir,
                half: [S::ZERO; 3],
                color: light.color,
            });
        }
    }
    out
}

/// Ambient + Lambert + Blinn-Phong at a unit normal (back end numbers),
/// 0..255 per channel: a vertex, or a fast-Phong edge midpoint.
#[inline]
fn shade_vec<S: Real>(
    n: Vec3<S>,
    kd: Rgb,
    ka: Rgb,
    m: &Material,
    lights: &[ModelLight<S>],
    ambient: &Vec3<S>,
) -> [u8; 3] {
    Lit::new(kd, ka, m, ambient).at(n, lights)
}

/// What [`shade_vec`] needs of a material and its colours, in the back
/// end's numbers: prepared once for a group of vertices that share them
/// (a mesh without vertex colours), not once a vertex.
#[derive(Clone, Copy)]
struct Lit<S> {
    /// `ka ambient`, per channel.
    base: Vec3<S>,
    kd: Vec3<S>,
    ks: Vec3<S>,
    specular: bool,
    ns: u8,
}

impl<S: Real> Lit<S> {
    #[inline]
    fn new(kd: Rgb, ka: Rgb, m: &Material, ambient: &Vec3<S>) -> Self {
        let ch = |c: Rgb| [c.r, c.g, c.b].map(|v| S::from_i32(v as i32));
        let ka = ch(ka);
        Lit {
            base: core::array::from_fn(|k| ka[k] * ambient[k]),
            kd: ch(kd),
            ks: ch(m.ks),
            specular: m.ks != Rgb::new(0, 0, 0),
            ns: m.ns.max(1),
        }
    }

    /// The colour at unit normal `n` under `lights`.
    #[inline]
    fn at(&self, n: Vec3<S>, lights: &[ModelLight<S>]) -> [u8; 3] {
        let (mut diff, mut spec) = ([S::ZERO; 3], [S::ZERO; 3]);
        for l in lights {
            let ndl = dot(n, l.dir);
            if ndl > S::ZERO {
                for (d, c) in diff.iter_mut().zip(l.color) {
                    *d = *d + c * ndl;
                }
                if self.specular {
                    let ndh = dot(n, l.half);
                    if ndh > S::ZERO {
                        let p = powi(ndh, self.ns);
                        for (s, c) in spec.iter_mut().zip(l.color) {
                            *s = *s + c * p;
                        }
                    }
                }
            }
        }
        core::array::from_fn(|k| {
            let v = self.base[k] + self.kd[k] * diff[k] + self.ks[k] * spec[k];
            v.to_fixed(0).unwrap_or(255).clamp(0, 255) as u8
        })
    }
}

/// `x^e` by squaring.
fn powi<S: Real>(x: S, mut e: u8) -> S {
    let (mut acc, mut b) = (S::ONE, x);
    while e > 0 {
        if e & 1 != 0 {
            acc = acc * b;
        }
        b = b * b;
        e >>= 1;
    }
    acc
}

impl<'a, S: Real, const D: usize> Scene<'a, S, D> {
    /// Calls `f(draw, triangle, piece)` for each of `keys` (increasing)
    /// that names a triangle of a draw.
    fn each_key(&self, keys: impl Iterator<Item = u32>, mut f: impl FnMut(&Draw<'a, S>, u16, u32)) {
        let mut di = 0;
        for key in keys {
            let tri = key >> 3;
            while di + 1 < self.draws.len() && tri >= self.draws[di + 1].tri_base {
                di += 1;
            }
            let Some(d) = self.draws.get(di) else { return };
            let Some(t) = tri.checked_sub(d.tri_base) else {
                continue;
            };
            if t >= d.mesh.triangles() as u32 {
                continue;
            }
            f(d, t as u16, key & 7);
        }
    }
}

impl<S: Real, const D: usize> CommandSource for Scene<'_, S, D> {
    fn each_keyed(&self, mut f: impl FnMut(u32, &Command)) -> Result<(), Error> {
        for d in &self.draws {
            for t in 0..d.mesh.triangles() {
                self.emit(d, t, |_| true, &mut f);
            }
        }
        Ok(())
    }

    fn replay(&self, keys: impl Iterator<Item = u32>, mut f: impl FnMut(&Command)) {
        self.each_key(keys, |d, t, piece| {
            self.emit(d, t, |p| p == piece, &mut |_, c| f(c))
        });
    }

    /// Binning reads each unclipped triangle's box and winding straight
    /// from the vertex cache (no command is built); clipped triangles, and
    /// frames with coverage antialiasing or a frame-level cull, go through
    /// [`CommandSource::each_keyed`].
    fn each_bounds(
        &self,
        cells: bool,
        area: bool,
        cull: Cull,
        mut f: impl FnMut(u32, Option<Rect>),
    ) -> Result<(), Error> {
        if cells || cull != Cull::None {
            return self.each_keyed(|k, c| f(k, crate::frame::bin_bounds(c, cells, area, cull)));
        }
        for d in &self.draws {
            // Which signs of the doubled area are drawn ([`faces`]),
            // decided once per draw rather than per triangle.
            let front = front_sign(&d.opts);
            let (pos, neg) = match d.opts.cull {
                Cull::None => (true, true),
                Cull::Back => (front > 0, front < 0),
                Cull::Front => (front < 0, front > 0),
            };
            let base = &self.cache[d.first as usize..];
            if d.front_bits {
                each_front(d, base, |t| {
                    let v = d.mesh.triangle(t).map(|i| &base[i as usize]);
                    let b = SubBox::of_points(v.map(|s| (s.v.x, s.v.y)));
                    f((d.tri_base + t as u32) << 3, b.pixels());
                });
                continue;
            }
            for t in 0..d.mesh.triangles() {
                let v = d.mesh.triangle(t).map(|i| &base[i as usize]);
                if v[0].v.code & v[1].v.code & v[2].v.code & ALL != 0 {
                    continue;
                }
                if (v[0].v.code | v[1].v.code | v[2].v.code) & ALL == 0 {
                    let a = self::area(&v);
                    if (a > 0 && pos) || (a < 0 && neg) {
                        let b = SubBox::of_points(v.map(|s| (s.v.x, s.v.y)));
                        f((d.tri_base + t as u32) << 3, b.pixels());
                    }
                    continue;
                }
                self.emit(d, t, |_| true, &mut |k, c| {
                    f(k, crate::frame::bin_bounds(c, cells, area, cull))
                });
            }
        }
        Ok(())
    }

    /// Unclipped Gouraud triangles go from the vertex cache straight to
    /// the tile ([`Tile::draw_mesh_triangle`](crate::tile::Tile)): no
    /// command is built or decoded; binning has culled their back faces.
    /// What a draw decides for all its triangles (which draw a key falls
    /// in, whether its triangles may go straight to the tile, their state
    /// when it does not depend on the group) is decided once a draw, not
    /// once a key (the M4 teapot: 119 -> 95 instructions a pair outside
    /// the tile, measured).
    fn draw_keys<const N: usize, C: TileConfig>(
        &self,
        keys: impl Iterator<Item = u32>,
        tile: &mut Tile<N, C>,
    ) -> u32 {
        let mut n = 0;
        let mut di = usize::MAX;
        // The current draw's triangle keys `[lo, hi)`, and whether they go
        // straight to the tile with one state.
        let (mut lo, mut hi, mut direct, mut state) = (u32::MAX, 0, false, State::default());
        // The draw's cache slots and mesh, and whether its triangles share
        // its state (untagged, or one group).
        let (mut base, mut mesh, mut shared): (&[VertexSlot], Option<&Mesh<'_>>, bool) =
            (&[], None, true);
        for key in keys {
            let tri = key >> 3;
            if !(lo..hi).contains(&tri) {
                // Keys increase: the draw is this one or a later one.
                let start = if di == usize::MAX || tri < lo { 0 } else { di };
                let Some(i) = (start..self.draws.len())
                    .rev()
                    .find(|&i| self.draws[i].tri_base <= tri)
                else {
                    continue;
                };
                let d = &self.draws[i];
                di = i;
                (lo, hi) = (d.tri_base, d.tri_base + d.mesh.triangles() as u32);
                direct = !(d.opts.shading != Shading::Gouraud && d.opts.lit);
                state = d.opts.state;
                base = &self.cache[d.first as usize..];
                mesh = Some(&d.mesh);
                shared = state.tag == 0 || d.mesh.groups() == 1;
                if tri >= hi {
                    continue;
                }
            }
            let t = (tri - lo) as u16;
            if let (true, 0, Some(mesh)) = (direct, key & 7, mesh) {
                let v = mesh.triangle(t).map(|i| &base[i as usize].v);
                if (v[0].code | v[1].code | v[2].code) & ALL == 0 {
                    if shared {
                        tile.draw_mesh_triangle(v, &state);
                    } else {
                        tile.draw_mesh_triangle(v, &tagged(mesh, &state, t));
                    }
                    n += 1;
                    continue;
                }
            }
            let d = &self.draws[di];
            self.emit(d, t, |p| p == key & 7, &mut |_, c| {
                tile.draw_valid(c, &[]);
                n += 1;
            });
        }
        n
    }
}
