//! Occlusion culling during rasterization, in one pass (seed 004): hidden
//! objects are found while the frame is drawn, from the depth already in
//! the tile, and never shaded — nor transformed, when no tile ever sees
//! them.
//!
//! **The pieces.**
//! - [`HiZ`]: a per-block depth summary of the tile (nearest and farthest
//!   Z of each `2^SHIFT` block, 4 bytes a block), kept as bounds per
//!   command. A box test counts the fragments of a screen rectangle at one
//!   depth that would pass the Z test, writing nothing; whole blocks are
//!   decided from the summary, only straddling blocks are read.
//! - [`KdTree`]: the application's spatial hierarchy over object boxes,
//!   built once, walked front to back.
//! - [`Culler`]: the walk, per tile, with the seed's temporal coherence:
//!   an inner node visible last frame is a *priority* node and is opened
//!   without a test (pull down happened before); every other node's box is
//!   tested against the tile, and a hidden one is skipped with all below
//!   it. A visible leaf's primitives are then drawn, each first tested
//!   against the summary (its rectangle at its nearest depth), so a hidden
//!   triangle skips setup and traversal. After the frame, visibility is
//!   pulled up the tree ([`Culler::end_frame`]) and kept for the next.
//! - [`Objects`]: where the walk gets a node's screen box and an object's
//!   commands. [`MeshObjects`] serves meshes through the geometry stage's
//!   [`Scene`], running an object's vertex stage the first time a tile
//!   finds it visible, so an object hidden everywhere is never transformed;
//!   its unclipped Gouraud triangles reach the walk as
//!   [`Primitive::Mesh`](crate::geometry::Primitive) and go from the vertex
//!   cache to the tile without a command being built (the fused mesh path,
//!   under the plane contract when the tile's configuration chooses it).
//!
//! **Tiles.** A tile holds part of the screen, so a node is tested in every
//! tile its screen box touches, against that tile's depth. The results
//! combine across the frame in one pass: a node is *visible* when any tile
//! found more than `threshold` fragments of its box visible; its fragment
//! count is the sum over tiles. A node skipped in one tile can still be
//! drawn in the next.
//!
//! **Exactness.** A box's screen rectangle covers every pixel its geometry
//! can touch and its depth is below every fragment's (two units of
//! margin), and depth only decreases while a tile is drawn; so with
//! threshold 0 a node is skipped only where none of its fragments would
//! pass the Z test, and the frame equals the unculled one pixel for pixel
//! (`tests/tests/occlusion.rs` checks every frame of camera paths). A
//! threshold `t > 0` (at most 128, the seed's 7 bits) skips nodes with up
//! to `t` visible fragments in a tile: faster, with pixels lost.
//! Culled objects must be opaque and depth-tested (what a Z-buffered 3D
//! scene is); draw translucent objects and overlays after.
//!
//! **The baselines**, on the same walk and rasterizer ([`CullMode`]):
//! stop-and-wait occlusion queries (every node's box is a pass over its
//! pixels, nothing written, its result awaited before going on) and CHC
//! (Bittner et al. 2004: nodes visible last frame are drawn without waiting
//! for their query; previously visible inner nodes are not queried). A
//! query pass reads every pixel of the box; the single-pass test reads
//! the summary. `tilerast-lab cull-report` measures all of them on the
//! same frames.
//!
//! ```
//! use tilerast::prelude::*;
//! use tilerast::geometry::*;
//! use tilerast::occlusion::*;
//!
//! // Two cubes on the view axis: the near one hides the far one.
//! let mut bytes = [0u8; CUBE_BYTES];
//! let cube = Mesh::cube(&mut bytes)?;
//! let items = [
//!     (cube, Mat4::translation([0.0, 0.0, 0.0])),
//!     (cube, Mat4::translation([0.0, 0.0, -4.0]).mul(&Mat4::scale([0.5; 3]))),
//! ];
//! let boxes = [Aabb::of_mesh(&items[0].0, &items[0].1), Aabb::of_mesh(&items[1].0, &items[1].1)];
//! let mut culler: Culler<f32, 3> = Culler::new(KdTree::build(&boxes)?);
//!
//! let eye = [0.0, 0.0, 5.0];
//! let mut slots = [VertexSlot::EMPTY; 48];
//! let mut scene: Scene<'_, f32, 2> = Scene::new(&mut slots);
//! scene.set_camera(Mat4::look_at(eye, [0.0; 3], [0.0, 1.0, 0.0])?,
//!                  Mat4::perspective(Angle::degrees(40), 1.0, 1.0, 20.0)?);
//! scene.set_viewport(Rect::new(0, 0, 32, 32))?;
//!
//! type T = Tile<{ groups(16, 16) }, St7789Config>;
//! let (frame, mut tile, mut hiz) = (T::frame::<16, 16>(32, 32)?, T::new(), HiZ::<4, 3>::new());
//! let mut objects = MeshObjects::new(&mut scene, &items, DrawOptions::default())?;
//! let stats = culler
//!     .render(CullMode::SinglePass, &frame, &mut tile, &mut hiz, eye, &mut objects, |_| Ok::<(), ()>(()))
//!     .map_err(|_| Error::BadSize)?;
//! assert!(culler.object_visible(0) && !culler.object_visible(1));
//! assert_eq!(objects.prepared(), 1); // the hidden cube was never transformed
//! assert!(stats.nodes_culled >= 1);
//! # Ok::<(), tilerast::Error>(())
//! ```

mod hiz;
mod kd;

pub use hiz::{HiZ, TestCost};
pub use kd::{Aabb, KdTree, Node, NodeKind};

use crate::command::Command;
use crate::config::TileConfig;
use crate::error::{Error, FlushError};
use crate::frame::Frame;
use crate::geometry::{DrawOptions, Mat4, Mesh, Primitive, Real, Scene, ScreenBox, Vec3};
use crate::raster::coverage::AaMode;
use crate::tile::Tile;

/// How a frame culls ([`Culler::render`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CullMode {
    /// No test: every object in the frustum is drawn, front to back.
    Off,
    /// Stop-and-wait occlusion queries: each node's box is a query pass
    /// over its pixels, awaited before descending.
    StopAndWait,
    /// Coherent hierarchical culling: nodes visible last frame are drawn
    /// without waiting (their leaves still queried for the next frame),
    /// previously visible inner nodes are not queried.
    Chc,
    /// The seed's single pass: box tests against the block summary,
    /// priority nodes opened without a test, primitives tested early.
    SinglePass,
}

impl CullMode {
    /// Every mode, in the report's order.
    pub const ALL: [CullMode; 4] = [
        CullMode::Off,
        CullMode::StopAndWait,
        CullMode::Chc,
        CullMode::SinglePass,
    ];

    /// Short name for reports and scene files.
    pub const fn name(self) -> &'static str {
        match self {
            CullMode::Off => "none",
            CullMode::StopAndWait => "s&w",
            CullMode::Chc => "chc",
            CullMode::SinglePass => "single-pass",
        }
    }
}

/// What culling a frame did, summed over its tiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CullStats {
    /// Tiles rendered.
    pub tiles: u32,
    /// Node visits (a node is visited in each tile its box touches).
    pub nodes_visited: u32,
    /// Node boxes projected to the screen (once per node per frame).
    pub boxes_projected: u32,
    /// Box tests (single pass) or queries (S&W, CHC).
    pub boxes_tested: u32,
    /// Node visits that skipped the node and everything below it.
    pub nodes_culled: u32,
    /// Leaf visits that drew their object.
    pub objects_drawn: u32,
    /// Primitives tested early against the summary (single pass).
    pub prims_tested: u32,
    /// Primitives the early test skipped.
    pub prims_culled: u32,
    /// Commands drawn into tiles.
    pub commands: u32,
    /// Fragments the box and primitive tests covered, and depth values
    /// they read.
    pub cost: TestCost,
}

impl core::ops::AddAssign for CullStats {
    fn add_assign(&mut self, s: Self) {
        self.tiles += s.tiles;
        self.nodes_visited += s.nodes_visited;
        self.boxes_projected += s.boxes_projected;
        self.boxes_tested += s.boxes_tested;
        self.nodes_culled += s.nodes_culled;
        self.objects_drawn += s.objects_drawn;
        self.prims_tested += s.prims_tested;
        self.prims_culled += s.prims_culled;
        self.commands += s.commands;
        self.cost.fragments += s.cost.fragments;
        self.cost.reads += s.cost.reads;
    }
}

/// Where the walk gets screen boxes and commands.
pub trait Objects<S> {
    /// The screen box of a world-space box, `None` when it lies outside the
    /// view (nothing inside can be drawn). Called once per node per frame.
    fn screen_box(&mut self, b: &Aabb<S>) -> Option<ScreenBox>;
    /// Calls `draw` with every command of object `object` (valid commands:
    /// opaque, depth-tested). Called in every tile where the object is
    /// drawn: an implementation prepares an object once per frame.
    fn commands(&mut self, object: u16, draw: &mut dyn FnMut(&Command));

    /// Calls `draw` with every primitive of object `object`: what the walk
    /// calls. By default each of [`commands`](Self::commands); a
    /// geometry-stage source ([`MeshObjects`]) hands its unclipped Gouraud
    /// triangles over as [`Primitive::Mesh`], which go from the vertex
    /// cache to the tile without a command.
    fn primitives(&mut self, object: u16, draw: &mut dyn FnMut(Primitive<'_>)) {
        self.commands(object, &mut |c| draw(Primitive::Command(c)));
    }
}

/// [`Objects`] from meshes placed by model matrices, through a geometry
/// [`Scene`] (which the caller has cleared for the frame and given camera,
/// viewport and lights): an object's vertex stage runs the first time it
/// is drawn in the frame, never for an object no tile sees.
pub struct MeshObjects<'s, 'a, S: Real, const D: usize> {
    scene: &'s mut Scene<'a, S, D>,
    items: &'s [(Mesh<'a>, Mat4<S>)],
    opts: DrawOptions,
    /// Per object: its draw index, or `UNSEEN` / `EMPTY`.
    draw: heapless::Vec<u16, D>,
    prepared: u32,
}

const UNSEEN: u16 = u16::MAX;
const EMPTY: u16 = u16::MAX - 1;

impl<'s, 'a, S: Real, const D: usize> MeshObjects<'s, 'a, S, D> {
    /// Objects `items` drawn with `opts`; [`Error::ListFull`] for more
    /// items than the scene has draws.
    pub fn new(
        scene: &'s mut Scene<'a, S, D>,
        items: &'s [(Mesh<'a>, Mat4<S>)],
        opts: DrawOptions,
    ) -> Result<Self, Error> {
        let mut draw = heapless::Vec::new();
        for _ in items {
            draw.push(UNSEEN).map_err(|_| Error::ListFull)?;
        }
        Ok(MeshObjects {
            scene,
            items,
            opts,
            draw,
            prepared: 0,
        })
    }

    /// Objects whose vertex stage ran this frame.
    pub fn prepared(&self) -> u32 {
        self.prepared
    }

    /// The scene (its [`Scene::stats`] sum the vertex stages that ran).
    pub fn scene(&self) -> &Scene<'a, S, D> {
        self.scene
    }
}

impl<S: Real, const D: usize> Objects<S> for MeshObjects<'_, '_, S, D> {
    fn screen_box(&mut self, b: &Aabb<S>) -> Option<ScreenBox> {
        self.scene.screen_box(b.lo, b.hi)
    }

    fn commands(&mut self, object: u16, draw: &mut dyn FnMut(&Command)) {
        if let Some(d) = self.prepare(object) {
            self.scene.each_of(d, |c| draw(c));
        }
    }

    fn primitives(&mut self, object: u16, draw: &mut dyn FnMut(Primitive<'_>)) {
        if let Some(d) = self.prepare(object) {
            self.scene.each_primitive_of(d, draw);
        }
    }
}

impl<S: Real, const D: usize> MeshObjects<'_, '_, S, D> {
    /// Object `object`'s draw index, its vertex stage run the first time
    /// it is asked for; `None` when it draws nothing.
    fn prepare(&mut self, object: u16) -> Option<usize> {
        let o = object as usize;
        let &d = self.draw.get(o)?;
        let d = if d == UNSEEN {
            let (mesh, model) = &self.items[o];
            let before = self.scene.draw_count();
            // A draw that fails (cache full, bad numbers) draws nothing,
            // as it would in an unculled frame.
            let _ = self.scene.draw(mesh, model, &self.opts);
            self.prepared += 1;
            let d = if self.scene.draw_count() > before {
                // Clipped once, not once per tile (when the cache has room).
                self.scene.keep_clipped(before);
                before as u16
            } else {
                EMPTY
            };
            self.draw[o] = d;
            d
        } else {
            d
        };
        (d != EMPTY).then_some(d as usize)
    }
}

impl<S: Real> Aabb<S> {
    /// The world-space box of `mesh` placed by `model` (the eight corners
    /// of its quantisation box, transformed).
    pub fn of_mesh(mesh: &Mesh<'_>, model: &Mat4<S>) -> Self {
        let c = mesh.center().map(|c| S::from_q(c as i64, 16));
        let e = S::from_q(mesh.extent() as i64, 16);
        let mut lo = [S::ZERO; 3];
        let mut hi = [S::ZERO; 3];
        for k in 0..8 {
            let corner: Vec3<S> = core::array::from_fn(|a| {
                if k & (1 << a) != 0 {
                    c[a] + e
                } else {
                    c[a] - e
                }
            });
            let p = model.transform(corner);
            for a in 0..3 {
                let v = p[a].div(p[3]);
                if k == 0 {
                    (lo[a], hi[a]) = (v, v);
                } else {
                    (lo[a], hi[a]) = (lo[a].min(v), hi[a].max(v));
                }
            }
        }
        Aabb { lo, hi }
    }
}

/// A node's screen box this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum BoxSlot {
    Unknown,
    Outside,
    At(ScreenBox),
}

/// The application side of seed 004 over a [`KdTree`] of `NODES` nodes:
/// the per-tile walk, the visibility fed back per node, and the history
/// that makes the next frame's priority nodes. About `NODES * (size of a
/// node + 26)` bytes.
pub struct Culler<S, const NODES: usize> {
    tree: KdTree<S, NODES>,
    /// Visible in the last finished frame.
    prev: [bool; NODES],
    /// Found visible in some tile this frame.
    seen: [bool; NODES],
    counts: [u32; NODES],
    boxes: [BoxSlot; NODES],
    threshold: u8,
    exact: bool,
    early_queries: bool,
    history: bool,
}

impl<S: Real, const NODES: usize> Culler<S, NODES> {
    /// A culler over `tree`, with no history (the first frame tests every
    /// node) and threshold 0 (exact).
    pub fn new(tree: KdTree<S, NODES>) -> Self {
        Culler {
            tree,
            prev: [false; NODES],
            seen: [false; NODES],
            counts: [0; NODES],
            boxes: [BoxSlot::Unknown; NODES],
            threshold: 0,
            exact: false,
            early_queries: false,
            history: false,
        }
    }

    /// The tree.
    pub fn tree(&self) -> &KdTree<S, NODES> {
        &self.tree
    }

    /// Sets the minimum visible fragments (in a tile) for a node to count as
    /// visible, `0..=128` ([`Error::BadSize`] beyond): 0 is exact.
    pub fn set_threshold(&mut self, t: u8) -> Result<(), Error> {
        if t > 128 {
            return Err(Error::BadSize);
        }
        self.threshold = t;
        Ok(())
    }

    /// Whether the single pass's box tests count every visible fragment
    /// (`true`) or stop at `threshold + 1`, enough to decide (`false`, the
    /// default: a visible node's test ends at its first visible
    /// fragments). With exact counts [`Culler::fragments`] is the seed's
    /// counter; without, it saturates at `threshold + 1` per tile. Either
    /// way the frame is the same.
    pub fn set_exact_counts(&mut self, exact: bool) {
        self.exact = exact;
    }

    /// Whether the baselines' queries ([`CullMode::StopAndWait`],
    /// [`CullMode::Chc`]) stop at `threshold + 1` too. By default they
    /// count every fragment of the box, as an occlusion query's pass does
    /// (`GL_SAMPLES_PASSED`); a software query can stop early as well,
    /// which this measures.
    pub fn set_early_queries(&mut self, early: bool) {
        self.early_queries = early;
    }

    /// Forgets the history: the next frame is a first frame.
    pub fn reset(&mut self) {
        self.history = false;
        self.prev = [false; NODES];
    }

    /// Whether node `i` was visible in the last frame rendered (pulled up:
    /// an inner node is visible when a child is).
    pub fn visible(&self, i: u16) -> bool {
        self.prev[i as usize]
    }

    /// Visible fragments of node `i`'s box in the last frame, summed over
    /// tiles (0 for a node opened without a test or skipped; per tile at
    /// most `threshold + 1` unless [`Culler::set_exact_counts`]).
    pub fn fragments(&self, i: u16) -> u32 {
        self.counts[i as usize]
    }

    /// Whether object `o` was visible in the last frame.
    pub fn object_visible(&self, o: u16) -> bool {
        (0..self.tree.len() as u16).any(|i| {
            matches!(self.tree.node(i).kind, NodeKind::Leaf(x) if x == o) && self.prev[i as usize]
        })
    }

    /// Renders a frame with `mode`: every tile of `frame` is cleared, walked
    /// front to back from `eye` (drawing what `objects` gives) and handed to
    /// `done`; then visibility is pulled up and kept for the next frame.
    /// `hiz` needs blocks for one tile ([`HiZ`]).
    #[allow(clippy::too_many_arguments)]
    pub fn render<const N: usize, C: TileConfig, const B: usize, const SH: u32, E>(
        &mut self,
        mode: CullMode,
        frame: &Frame,
        tile: &mut Tile<N, C>,
        hiz: &mut HiZ<B, SH>,
        eye: Vec3<S>,
        objects: &mut impl Objects<S>,
        mut done: impl FnMut(&mut Tile<N, C>) -> Result<(), E>,
    ) -> Result<CullStats, FlushError<E>> {
        self.seen = [false; NODES];
        self.counts = [0; NODES];
        self.boxes = [BoxSlot::Unknown; NODES];
        let mut st = CullStats::default();
        for area in frame.tiles() {
            tile.begin(area, &frame.clear)?;
            hiz.reset_to(area, frame.clear.depth);
            self.walk(mode, tile, hiz, eye, objects, &mut st);
            // Coverage antialiasing: spans and lines over the resolved
            // pixels (the walk's tests stay conservative).
            if tile.finish() {
                self.walk(mode, tile, hiz, eye, objects, &mut st);
            }
            done(tile).map_err(FlushError::Target)?;
            st.tiles += 1;
        }
        if mode != CullMode::Off {
            self.end_frame();
        }
        Ok(st)
    }

    /// Pull up: a leaf is visible when some tile drew it; an inner node when
    /// a child is. Becomes the next frame's priority set.
    pub fn end_frame(&mut self) {
        for i in (0..self.tree.len()).rev() {
            self.prev[i] = match self.tree.node(i as u16).kind {
                NodeKind::Leaf(_) => self.seen[i],
                NodeKind::Inner { lo, hi, .. } => self.prev[lo as usize] || self.prev[hi as usize],
            };
        }
        self.history = true;
    }

    /// One tile's walk.
    fn walk<const N: usize, C: TileConfig, const B: usize, const SH: u32>(
        &mut self,
        mode: CullMode,
        tile: &mut Tile<N, C>,
        hiz: &mut HiZ<B, SH>,
        eye: Vec3<S>,
        objects: &mut impl Objects<S>,
        st: &mut CullStats,
    ) {
        let area = tile.area();
        let thr = self.threshold as u32;
        let early = match mode {
            CullMode::SinglePass => !self.exact,
            _ => self.early_queries,
        };
        let limit = if early { thr + 1 } else { u32::MAX };
        let aa = <C::Aa as AaMode>::SAMPLES > 0;
        let area_aa = <C::Aa as AaMode>::AREA;
        let mut stack: heapless::Vec<u16, 64> = heapless::Vec::new();
        let _ = stack.push(0);
        while let Some(n) = stack.pop() {
            st.nodes_visited += 1;
            let ni = n as usize;
            let node = *self.tree.node(n);
            if self.boxes[ni] == BoxSlot::Unknown {
                st.boxes_projected += 1;
                self.boxes[ni] = match objects.screen_box(&node.bounds) {
                    Some(b) => BoxSlot::At(b),
                    None => BoxSlot::Outside,
                };
            }
            let BoxSlot::At(sb) = self.boxes[ni] else {
                continue;
            };
            let Some(r) = sb.rect.intersect(&area) else {
                continue;
            };
            let inner = matches!(node.kind, NodeKind::Inner { .. });
            let prev = self.history && self.prev[ni];
            // (test the box, with the summary, wait for the answer)
            let (test, summary, wait) = match mode {
                CullMode::Off => (false, false, false),
                CullMode::StopAndWait => (true, false, true),
                CullMode::Chc => (!(prev && inner), false, !prev),
                CullMode::SinglePass => (!(prev && inner), true, true),
            };
            if test {
                st.boxes_tested += 1;
                let c = hiz.count(tile, r, sb.z, summary, limit, &mut st.cost);
                self.counts[ni] += c;
                let vis = c > thr;
                self.seen[ni] |= vis;
                if wait && !vis {
                    st.nodes_culled += 1;
                    continue;
                }
            }
            match node.kind {
                NodeKind::Inner { .. } => {
                    if let Some((near, far)) = self.tree.near_far(n, eye) {
                        let _ = stack.push(far);
                        let _ = stack.push(near);
                    }
                }
                NodeKind::Leaf(o) => {
                    st.objects_drawn += 1;
                    let early = mode == CullMode::SinglePass;
                    let track = mode != CullMode::Off;
                    objects.primitives(o, &mut |p: Primitive<'_>| {
                        // A mesh triangle goes straight to the tile, unless
                        // coverage AA needs its command's wider bounds.
                        let made;
                        let p = match p {
                            Primitive::Mesh(t) if aa || area_aa => {
                                made = t.command();
                                Primitive::Command(&made)
                            }
                            p => p,
                        };
                        let (b, near) = match p {
                            Primitive::Command(cmd) => (
                                if aa || area_aa && cmd.edge_flagged() {
                                    cmd.coverage_bounds()
                                } else {
                                    cmd.bounds()
                                },
                                nearest(cmd),
                            ),
                            Primitive::Mesh(t) => (t.bounds(), Some(t.nearest())),
                        };
                        let Some(b) = b.and_then(|b| b.intersect(&area)) else {
                            return;
                        };
                        let near = near.map(|z| z.saturating_sub(2));
                        if early {
                            if let Some(z) = near {
                                st.prims_tested += 1;
                                if hiz.count(tile, b, z, true, 1, &mut st.cost) == 0 {
                                    st.prims_culled += 1;
                                    return;
                                }
                            }
                        }
                        match p {
                            Primitive::Command(cmd) => tile.draw_valid(cmd, &[]),
                            Primitive::Mesh(t) => t.draw(tile),
                        }
                        st.commands += 1;
                        if track {
                            // Opaque, depth-tested triangles keep the
                            // blocks' bounds; anything else marks them stale.
                            match near {
                                Some(z) => hiz.touch_near(&b, z),
                                None => hiz.touch(&b),
                            }
                        }
                    });
                }
            }
        }
    }
}

/// The nearest vertex depth of a triangle command.
fn nearest(cmd: &Command) -> Option<u16> {
    let z = match cmd {
        Command::Triangle { v, .. } => v.map(|v| v.z),
        Command::Quadratic { v, .. } => v.map(|q| q.vertex().z),
        _ => return None,
    };
    Some(z[0].min(z[1]).min(z[2]))
}
