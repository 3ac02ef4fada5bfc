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

/// Whether every position a mesh can hold (`[i16::MIN, i16::MAX]^3`, as
/// [`Real::affine_q15`] feeds them to the rows of `m`, a `bounded` matrix)
/// has outcode 0 against guard band `g`, by the same arithmetic: the box's
/// 8 corners each lie inside every plane by a margin no rounding can
/// cross. A plane's value is linear in the position, so its exact value at
/// any position is at least its least exact value at a corner; each
/// computed value is within a few units in the last place (`Fx`: 2^-16,
/// times `1 + g` through `g w`) or a few `2^-24` of the row's magnitude
/// (`f32`) of the exact one. The margin, `2^-10 (1 + g)` plus `2^-16`
/// times the magnitude, is far above both errors together, so a `true`
/// here means [`outcode`] would return 0 for every vertex: the vertex
/// stage may skip it ([`super::Scene::draw`]). A box near a plane (within
/// the margin) gets `false`, and its vertices take the per-vertex test.
pub(crate) fn box_inside<S: Real>(m: &[[S; 4]; 4], g: [S; 2]) -> bool {
    let abs = |v: S| v.max(-v);
    let qmax = S::from_q15(i16::MAX).max(-S::from_q15(i16::MIN));
    // Each row's largest magnitude over the box.
    let mag: [S; 4] = core::array::from_fn(|k| {
        (abs(m[k][0]) + abs(m[k][1]) + abs(m[k][2])) * qmax + abs(m[k][3])
    });
    let (ulps, rel) = (S::from_q(1, 10), S::from_q(1, 16));
    let margin = |bit: u8| match bit {
        NEAR => ulps + mag[2] * rel,
        FAR => ulps + (mag[2] + mag[3]) * rel,
        LEFT | RIGHT => (S::ONE + g[0]) * ulps + (mag[0] + g[0] * mag[3]) * rel,
        _ => (S::ONE + g[1]) * ulps + (mag[1] + g[1] * mag[3]) * rel,
    };
    let q = [i16::MIN, i16::MAX];
    (0..8).all(|k| {
        let c = [q[k & 1], q[k >> 1 & 1], q[k >> 2]];
        let p = m.map(|row| S::affine_q15(&row, c, true));
        [NEAR, FAR, LEFT, RIGHT, BOTTOM, TOP]
            .into_iter()
            .all(|bit| dist(&p, bit, g) >= margin(bit))
    })
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

    /// A random matrix in the vertex stage's folded form (`f32`: the
    /// position columns times 2^-15) that puts the box in front of the
    /// camera, its `x` and `y` spread scaled by `spread` (near 1: the box
    /// grazes the guard band `g`).
    fn matrix<S: Real>(next: &mut impl FnMut() -> f64, spread: f64, g: f64) -> [[S; 4]; 4] {
        let w3 = 4.0 + 4.0 * next();
        let w: [f64; 3] = core::array::from_fn(|_| next() - 0.5);
        let wmin = w3 - w.iter().map(|v| v.abs()).sum::<f64>();
        // |x| at most `spread g wmin` over the box.
        let xy = |n: &mut dyn FnMut() -> f64| {
            let r: [f64; 4] = core::array::from_fn(|_| n() - 0.5);
            let sum = r.iter().map(|v| v.abs()).sum::<f64>();
            r.map(|v| v / sum * spread * g * wmin)
        };
        let x = xy(next);
        let y = xy(next);
        let z = [0.3 * w[0], 0.3 * w[1], 0.3 * w[2], 0.5 * w3];
        let fold = if S::FOLD_Q15 { 1.0 / 32768.0 } else { 1.0 };
        [x, y, z, [w[0], w[1], w[2], w3]].map(|r| {
            core::array::from_fn(|k| {
                let v = if k < 3 { r[k] * fold } else { r[k] };
                S::from_q((v * (1u64 << 40) as f64) as i64, 40)
            })
        })
    }

    /// `box_inside` is sound: when it holds, every position's outcode,
    /// computed as the vertex stage computes it, is 0 — the box's corners,
    /// positions next to them and random ones — for boxes well inside and
    /// boxes grazing the guard band; and it holds for a box well inside.
    fn box_inside_is_sound<S: Real>() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut held, mut grazing) = (0, 0);
        for case in 0..400 {
            let g = 1.0 + 100.0 * next();
            let spread = if case % 2 == 0 {
                0.5
            } else {
                0.999 + 0.002 * next()
            };
            let m = matrix::<S>(&mut next, spread, g);
            let gs = [g, g].map(|g| S::from_q((g * 65536.0) as i64, 16));
            let inside = box_inside(&m, gs);
            if case % 2 == 0 {
                assert!(inside, "case {case}: a box well inside");
            }
            if !inside {
                continue;
            }
            held += 1;
            grazing += (case % 2) as u32;
            let e = [i16::MIN, i16::MIN + 1, -1, 0, 1, i16::MAX - 1, i16::MAX];
            let mut q = [0i16; 3];
            for k in 0..(7 * 7 * 7 + 300) {
                q = if k < 343 {
                    [e[k % 7], e[k / 7 % 7], e[k / 49]]
                } else {
                    q.map(|_| (next() * 65536.0 - 32768.0) as i16)
                };
                let p = m.map(|row| S::affine_q15(&row, q, true));
                assert_eq!(outcode(&p, gs), 0, "case {case}: {q:?}");
            }
        }
        assert!(held > 200 && grazing > 0, "{held} {grazing}");
    }

    #[test]
    fn box_inside_is_sound_in_f32() {
        box_inside_is_sound::<f32>();
    }

    #[test]
    fn box_inside_is_sound_in_fixed_point() {
        box_inside_is_sound::<crate::geometry::Fx>();
    }
}
