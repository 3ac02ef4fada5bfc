//! The spatial hierarchy of seed 004 §3.1.2: a k-d tree over the scene's
//! objects, built once (at start-up or offline) and fixed afterwards,
//! walked front to back from the camera.
//!
//! Each object's world-space box is a leaf; an inner node splits its
//! objects at the median centre along the longest axis of their centres
//! and keeps the union box. Nodes are stored parent before children
//! (pre-order), so a reverse pass visits children before parents (the
//! pull-up of [`super::Culler::end_frame`]).

use crate::error::Error;
use crate::geometry::{Real, Vec3};

/// A world-space box, `lo..=hi` on each axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Aabb<S> {
    /// Smallest corner.
    pub lo: Vec3<S>,
    /// Largest corner.
    pub hi: Vec3<S>,
}

impl<S: Real> Aabb<S> {
    /// The box `lo..=hi`.
    pub const fn new(lo: Vec3<S>, hi: Vec3<S>) -> Self {
        Aabb { lo, hi }
    }

    /// The smallest box holding both.
    pub fn union(&self, o: &Self) -> Self {
        Aabb {
            lo: core::array::from_fn(|a| self.lo[a].min(o.lo[a])),
            hi: core::array::from_fn(|a| self.hi[a].max(o.hi[a])),
        }
    }

    /// Twice the centre (no halving: only compared).
    fn center2(&self) -> Vec3<S> {
        core::array::from_fn(|a| self.lo[a] + self.hi[a])
    }
}

/// What a node is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NodeKind<S> {
    /// One object (its index in the build input).
    Leaf(u16),
    /// Two subtrees split on `axis` at `split` (twice the coordinate): the
    /// `lo` child holds the objects whose centres lie below.
    Inner {
        /// 0, 1 or 2.
        axis: u8,
        /// Twice the split coordinate.
        split: S,
        /// Node index of the lower half.
        lo: u16,
        /// Node index of the upper half.
        hi: u16,
    },
}

/// A node: its box and what it holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node<S> {
    /// The union of the boxes below.
    pub bounds: Aabb<S>,
    /// Leaf or inner node.
    pub kind: NodeKind<S>,
}

/// A k-d tree of at most `NODES` nodes (`2 n - 1` for `n` objects) over
/// object boxes.
///
/// ```
/// use tilerast::occlusion::{Aabb, KdTree};
/// let boxes: Vec<Aabb<f32>> = (0..5)
///     .map(|i| Aabb::new([i as f32, 0.0, 0.0], [i as f32 + 0.5, 1.0, 1.0]))
///     .collect();
/// let tree: KdTree<f32, 9> = KdTree::build(&boxes)?;
/// assert_eq!(tree.len(), 9);
/// // Front to back from a camera at x = 10: object 4 first, object 0 last.
/// let mut order = vec![];
/// tree.front_to_back([10.0, 0.5, 0.5], |o| order.push(o));
/// assert_eq!(order, [4, 3, 2, 1, 0]);
/// # Ok::<(), tilerast::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct KdTree<S, const NODES: usize> {
    nodes: heapless::Vec<Node<S>, NODES>,
}

impl<S: Real, const NODES: usize> KdTree<S, NODES> {
    /// Builds the tree over `boxes` (at most `u16::MAX` objects;
    /// [`Error::ListFull`] when `2 n - 1` nodes exceed `NODES`,
    /// [`Error::BadSize`] for no object, [`Error::NotFinite`] for a box
    /// with a non-finite or inverted corner). No allocation: object indices
    /// are sorted (insertion sort, `O(n²)` at worst: milliseconds for the
    /// hundreds of objects a device holds) in a scratch array of `NODES`
    /// entries on the stack.
    pub fn build(boxes: &[Aabb<S>]) -> Result<Self, Error> {
        let n = boxes.len();
        if n == 0 || n > u16::MAX as usize {
            return Err(Error::BadSize);
        }
        if 2 * n - 1 > NODES {
            return Err(Error::ListFull);
        }
        for b in boxes {
            let ok =
                (0..3).all(|a| b.lo[a].is_finite() && b.hi[a].is_finite() && b.lo[a] <= b.hi[a]);
            if !ok {
                return Err(Error::NotFinite);
            }
        }
        let mut order = [0u16; NODES];
        for (i, o) in order.iter_mut().enumerate().take(n) {
            *o = i as u16;
        }
        let mut tree = KdTree {
            nodes: heapless::Vec::new(),
        };
        tree.split(boxes, &mut order[..n]);
        Ok(tree)
    }

    /// Builds the subtree over `objs` and returns its node index.
    fn split(&mut self, boxes: &[Aabb<S>], objs: &mut [u16]) -> u16 {
        let at = self.nodes.len() as u16;
        let bounds = objs
            .iter()
            .skip(1)
            .fold(boxes[objs[0] as usize], |acc, &o| {
                acc.union(&boxes[o as usize])
            });
        // Capacity was checked: 2 n - 1 nodes for n objects.
        let _ = self.nodes.push(Node {
            bounds,
            kind: NodeKind::Leaf(objs[0]),
        });
        if objs.len() == 1 {
            return at;
        }
        // The longest axis of the centres' spread.
        let c0 = boxes[objs[0] as usize].center2();
        let (mut lo, mut hi) = (c0, c0);
        for &o in objs.iter() {
            let c = boxes[o as usize].center2();
            for a in 0..3 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        let mut axis = 0;
        for a in 1..3 {
            if hi[a] - lo[a] > hi[axis] - lo[axis] {
                axis = a;
            }
        }
        // Insertion sort by centre (ties by index: deterministic).
        let key = |o: u16| boxes[o as usize].center2()[axis];
        for i in 1..objs.len() {
            let mut j = i;
            while j > 0 && {
                let (a, b) = (key(objs[j - 1]), key(objs[j]));
                // Finite keys (checked): a total order.
                match b.partial_cmp(&a) {
                    Some(core::cmp::Ordering::Less) => true,
                    Some(core::cmp::Ordering::Equal) => objs[j] < objs[j - 1],
                    _ => false,
                }
            } {
                objs.swap(j - 1, j);
                j -= 1;
            }
        }
        let mid = objs.len() / 2;
        let split = key(objs[mid]);
        let (a, b) = objs.split_at_mut(mid);
        let lo_node = self.split(boxes, a);
        let hi_node = self.split(boxes, b);
        self.nodes[at as usize].kind = NodeKind::Inner {
            axis: axis as u8,
            split,
            lo: lo_node,
            hi: hi_node,
        };
        at
    }

    /// Nodes in the tree.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tree has no node (never, once built).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Node `i` (0 is the root; parents come before children).
    pub fn node(&self, i: u16) -> &Node<S> {
        &self.nodes[i as usize]
    }

    /// The children of inner node `i` nearer-first as seen from `eye`.
    pub fn near_far(&self, i: u16, eye: Vec3<S>) -> Option<(u16, u16)> {
        match self.nodes[i as usize].kind {
            NodeKind::Leaf(_) => None,
            NodeKind::Inner {
                axis,
                split,
                lo,
                hi,
            } => {
                let e = eye[axis as usize] + eye[axis as usize];
                Some(if e < split { (lo, hi) } else { (hi, lo) })
            }
        }
    }

    /// Calls `f` with every object, front to back from `eye`.
    pub fn front_to_back(&self, eye: Vec3<S>, mut f: impl FnMut(u16)) {
        let mut stack: heapless::Vec<u16, 64> = heapless::Vec::new();
        let _ = stack.push(0);
        while let Some(i) = stack.pop() {
            match self.near_far(i, eye) {
                None => {
                    if let NodeKind::Leaf(o) = self.nodes[i as usize].kind {
                        f(o)
                    }
                }
                Some((near, far)) => {
                    // Depth is at most log2(n) + 1 < 32: two entries a level.
                    let _ = stack.push(far);
                    let _ = stack.push(near);
                }
            }
        }
    }
}
