//! Clipping in homogeneous clip space (Sutherland–Hodgman): a triangle that
//! crosses the near or far plane, or leaves the guard band, is cut into a
//! convex polygon of at most 9 vertices and split into triangles, never
//! dropped. Attributes (colour) are interpolated linearly in clip space,
//! which is perspective-correct along the cut edges.

use super::real::Real;

/// Outcode bits: which side of each plane a clip-space point lies on.
pub(crate) const NEAR: u8 = 1;
/// Beyond the far plane.
pub(crate) const FAR: u8 = 2;
/// Left of the guard band.
pub(crate) const LEFT: u8 = 4;
/// Right of the guard band.
pub(crate) const RIGHT: u8 = 8;
/// Below the guard band.
pub(crate) const BOTTOM: u8 = 16;
/// Above the guard band.
pub(crate) const TOP: u8 = 32;
/// The outcode bits, together.
pub(crate) const ALL: u8 = 63;

/// A polygon vertex: clip position and colour (0..255 scale).
#[derive(Clone, Copy, Default, Debug)]
pub(crate) struct ClipVertex<S> {
    pub p: [S; 4],
    pub c: [S; 3],
}

/// Signed distance-like value of `p` to plane `bit` (inside when `>= 0`);
/// `g` = the guard band's half-size in `w` units, per axis.
#[inline]
fn dist<S: Real>(p: &[S; 4], bit: u8, g: [S; 2]) -> S {
    let [x, y, z, w] = *p;
    match bit {
        NEAR => z,
        FAR => w - z,
        LEFT => x + g[0] * w,
        RIGHT => g[0] * w - x,
        BOTTOM => y + g[1] * w,
        _ => g[1] * w - y,
    }
}

/// The outcode of `p` against the view volume's depth range and the guard
/// band (`g`: half-sizes in `w` units, `[1, 1]` for the view frustum).
#[inline]
pub(crate) fn outcode<S: Real>(p: &[S; 4], g: [S; 2]) -> u8 {
    let mut code = 0;
    for bit in [NEAR, FAR, LEFT, RIGHT, BOTTOM, TOP] {
        if dist(p, bit, g) < S::ZERO {
            code |= bit;
        }
    }
    code
}

/// Up to 9 vertices: a triangle cut by six planes gains at most one vertex
/// per plane. Two buffers, each plane's pass reading one and writing the
/// other: no polygon is copied per plane (the M4 city walk spent ~80 K
/// instructions a frame copying and zeroing 252-byte polygons).
pub(crate) struct Polygon<S> {
    buf: [[ClipVertex<S>; 9]; 2],
    cur: usize,
    n: usize,
}

impl<S: Copy> Polygon<S> {
    /// The polygon's vertices, in order.
    pub(crate) fn vertices(&self) -> &[ClipVertex<S>] {
        &self.buf[self.cur][..self.n]
    }
}

/// Clips triangle `tri` against the planes in `planes` (outcode bits).
pub(crate) fn clip<S: Real>(tri: [ClipVertex<S>; 3], planes: u8, g: [S; 2]) -> Polygon<S> {
    let mut poly = Polygon {
        buf: [[ClipVertex::default(); 9]; 2],
        cur: 0,
        n: 3,
    };
    poly.buf[0][..3].copy_from_slice(&tri);
    for bit in [NEAR, FAR, LEFT, RIGHT, BOTTOM, TOP] {
        if planes & bit == 0 || poly.n == 0 {
            continue;
        }
        let [b0, b1] = &mut poly.buf;
        let (src, out) = if poly.cur == 0 { (b0, b1) } else { (b1, b0) };
        let n = poly.n;
        let mut m = 0;
        for i in 0..n {
            let a = src[i];
            let b = src[(i + 1) % n];
            let (da, db) = (dist(&a.p, bit, g), dist(&b.p, bit, g));
            let (ina, inb) = (da >= S::ZERO, db >= S::ZERO);
            if ina && m < 9 {
                out[m] = a;
                m += 1;
            }
            if ina != inb && m < 9 {
                // From the inside end, always: the triangle on the other
                // side of this edge walks it the other way round and must
                // compute the same bits, or a crack opens between them.
                let (i, o, di, dout) = if ina { (a, b, da, db) } else { (b, a, db, da) };
                let t = di.div(di - dout);
                let lerp = |x: S, y: S| x + (y - x) * t;
                out[m] = ClipVertex {
                    p: core::array::from_fn(|k| lerp(i.p[k], o.p[k])),
                    c: core::array::from_fn(|k| lerp(i.c[k], o.c[k])),
                };
                m += 1;
            }
        }
        poly.cur ^= 1;
        poly.n = m;
    }
    poly
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cv(x: f32, y: f32, z: f32, w: f32) -> ClipVertex<f32> {
        ClipVertex {
            p: [x, y, z, w],
            c: [0.0; 3],
        }
    }

    #[test]
    fn near_plane_cuts_one_corner_into_a_quad() {
        let g = [10.0, 10.0];
        let t = [
            cv(0.0, 0.0, -1.0, 1.0),
            cv(1.0, 0.0, 1.0, 2.0),
            cv(0.0, 1.0, 1.0, 2.0),
        ];
        let p = clip(t, NEAR, g);
        assert_eq!(p.vertices().len(), 4);
        for v in p.vertices() {
            assert!(v.p[2] >= -1e-6, "{:?}", v.p);
        }
    }

    #[test]
    fn all_planes_keep_a_convex_polygon_inside() {
        let g = [1.0, 1.0];
        let t = [
            cv(-5.0, -5.0, 0.5, 1.0),
            cv(5.0, -5.0, 0.5, 1.0),
            cv(0.0, 5.0, 0.5, 1.0),
        ];
        let p = clip(t, ALL, g);
        assert!((4..=9).contains(&p.vertices().len()));
        for v in p.vertices() {
            assert_eq!(outcode(&v.p, [1.0001, 1.0001]), 0, "{:?}", v.p);
        }
    }
}
