//! Silhouette and boundary edges of a set of screen triangles: the edges
//! the wireframe and edge-antialiasing modes draw (seed 003) and the ones
//! area sampling blends ([`tilerast::area`]). Shared by the mesh loader
//! and the renderer, below both.

use tilerast::line::{EdgeCmd, Side};
use tilerast::prelude::*;

/// The edges of a triangle set that border something else on screen: those
/// of one triangle only (an open boundary) and those whose triangles all lie
/// on the same side of the edge (a fold: the silhouette). Edges are matched
/// by their end points' sub-pixel positions, so vertices an OBJ duplicates at
/// texture seams still join. Degenerate triangles take no part. The edge
/// gets the first triangle's vertices (colour and depth) and its side.
pub fn silhouette_edges(tris: &[[Vertex; 3]]) -> Vec<EdgeCmd> {
    let sides = EdgeSides::of(tris.iter());
    sides
        .order
        .iter()
        .filter_map(|k| {
            let (e, right, left) = sides.seen[k];
            (right != left).then_some(e)
        })
        .collect()
}

/// Flags ([`Vertex::edge_flag`]) every edge of the triangle commands that
/// [`silhouette_edges`] would return — those the area-sampling mode
/// ([`tilerast::area`]) antialiases — and clears the others, so the
/// triangles of one surface stay seamless.
pub fn flag_silhouettes(cmds: &mut [Command]) {
    let tris = cmds.iter().filter_map(|c| match c {
        Command::Triangle { v, .. } => Some(v),
        _ => None,
    });
    let sides = EdgeSides::of(tris);
    for c in cmds.iter_mut() {
        if let Command::Triangle { v, .. } = c {
            let keys: [_; 3] = core::array::from_fn(|i| EdgeSides::key(&v[i], &v[(i + 1) % 3]));
            for (i, k) in keys.iter().enumerate() {
                v[i].edge_flag = sides.seen.get(k).is_some_and(|&(_, r, l)| r != l);
            }
        }
    }
}

type Key = (i32, i32);

/// Per undirected screen edge of a set of triangles: the first triangle's
/// edge and the sides its triangles were seen on, in first-seen order.
struct EdgeSides {
    seen: std::collections::BTreeMap<(Key, Key), (EdgeCmd, bool, bool)>,
    order: Vec<(Key, Key)>,
}

impl EdgeSides {
    fn key(a: &Vertex, b: &Vertex) -> (Key, Key) {
        let (a, b) = (
            (a.x.to_bits(), a.y.to_bits()),
            (b.x.to_bits(), b.y.to_bits()),
        );
        (a.min(b), a.max(b))
    }

    fn of<'a>(tris: impl Iterator<Item = &'a [Vertex; 3]>) -> Self {
        let mut s = EdgeSides {
            seen: Default::default(),
            order: Vec::new(),
        };
        for t in tris {
            let p = t.map(|v| (v.x.to_bits() as i64, v.y.to_bits() as i64));
            let area =
                (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0);
            if area == 0 {
                continue;
            }
            for i in 0..3 {
                let e = EdgeCmd::of_triangle(t, i);
                let k = Self::key(&e.v[0], &e.v[1]);
                let a = (e.v[0].x.to_bits(), e.v[0].y.to_bits());
                // The side as seen from the edge's canonical direction.
                let right = (e.interior == Side::Right) == (a == k.0);
                let entry = s.seen.entry(k).or_insert_with(|| {
                    s.order.push(k);
                    (e, false, false)
                });
                if right {
                    entry.1 = true;
                } else {
                    entry.2 = true;
                }
            }
        }
        s
    }
}
