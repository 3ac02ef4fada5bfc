//! Slicing (seed 002 §3.1, Fig. 1): planes parallel to the image plane,
//! farthest first, each cut to the volume's box and mapped to 3D texture
//! coordinates.
//!
//! A view-aligned slice lies at one eye-space depth `c`, so on it the
//! projection's `w` is constant and the map from screen pixels to voxel
//! coordinates is **affine**, even in perspective: `t(px, py) = t0 + tx px
//! + ty py`. It is set up once per slice in the geometry stage's numbers
//! ([`Real`]: `f32` or `Fx`, bit-exact across targets), then stepped in
//! 16.16 fixed point. The slice polygon — the plane cut by the box — is the
//! set of pixels where `0 <= t_i <= dims_i - 1` on all three axes: six
//! half-planes, its edge functions. Each row's span is solved from them
//! exactly in integers (no per-pixel test, no sample outside the volume,
//! the same span whatever the tile), the way traversal solves a triangle's
//! three ([`crate::raster`]).

use super::data::Volume;
use crate::error::Error;
use crate::geom::Rect;
use crate::geometry::{Mat4, Real};

/// One slice, ready to scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slice {
    /// The slice's depth, 16-bit like vertices' (`0` near, `65535` far):
    /// a sample is composited only where it is nearer than the depth plane.
    pub z: u16,
    /// Pixels the slice may cover (conservative); its top-left is the
    /// anchor of `t0`.
    pub bounds: Rect,
    /// Voxel coordinates (16.16) at the anchor pixel's centre.
    pub(crate) t0: [i32; 3],
    /// Their steps per pixel in x.
    pub(crate) tx: [i32; 3],
    /// Their steps per row.
    pub(crate) ty: [i32; 3],
    /// Whether [`Slice::row`] may solve in `i32`.
    narrow: bool,
}

impl Slice {
    /// The covered pixels of row `py` inside `[lo, hi)` and the voxel
    /// coordinate at the first: `(x0, x1, t)`, `x0 >= x1` when none.
    /// Solved exactly from the six half-planes `bot_i <= t_i <= top_i`
    /// (the volume's box, or the box of its visible cells), in
    /// `i32` when the slice's numbers are small enough for every step to
    /// fit ([`Slice::narrow`]; a 32-bit division, one instruction with a
    /// divider), else in `i64`: the same span either way.
    #[inline]
    pub(crate) fn row(
        &self,
        py: i32,
        lo: i32,
        hi: i32,
        [bot, top]: [[i32; 3]; 2],
    ) -> (i32, i32, [i32; 3]) {
        if self.narrow {
            self.solve::<i32>(py, lo, hi, bot, top)
        } else {
            self.solve::<i64>(py, lo, hi, bot, top)
        }
    }

    /// [`Slice::row`] in `T`.
    #[inline(always)]
    fn solve<T: RowInt>(
        &self,
        py: i32,
        lo: i32,
        hi: i32,
        bot: [i32; 3],
        top: [i32; 3],
    ) -> (i32, i32, [i32; 3]) {
        let ax = self.bounds.x;
        let dy = T::from(py - self.bounds.y);
        // Columns relative to the anchor: k = px - ax.
        let (mut k0, mut k1) = (T::from(lo - ax), T::from(hi - ax));
        let zero = T::from(0);
        let mut base = [zero; 3];
        for i in 0..3 {
            // t_i(k) = b + tx k.
            let b = T::from(self.t0[i]) + T::from(self.ty[i]) * dy;
            base[i] = b;
            let (tx, bot, top) = (T::from(self.tx[i]), T::from(bot[i]), T::from(top[i]));
            if tx == zero {
                if b < bot || b > top {
                    return (0, 0, [0; 3]);
                }
                continue;
            }
            // With d = |tx|: bot <= b + tx k <= top holds from
            // k = -floor((b - bot) / d) (tx > 0) or -floor((top - b) / d)
            // (tx < 0) up to floor((top - b) / d), respectively
            // floor((b - bot) / d).
            let d = if tx > zero { tx } else { zero - tx };
            let (under, over) = ((b - bot).div_floor(d), (top - b).div_floor(d));
            let (from, to) = if tx > zero {
                (zero - under, over)
            } else {
                (zero - over, under)
            };
            k0 = k0.max(from);
            k1 = k1.min(to + T::from(1));
        }
        if k0 >= k1 {
            return (0, 0, [0; 3]);
        }
        // The first sample lies in the volume: exact even where the
        // product wraps.
        let t = core::array::from_fn(|i| base[i].low_plus(self.tx[i], k0));
        (ax + k0.low(), ax + k1.low(), t)
    }
}

/// The integers [`Slice::row`] solves in.
trait RowInt:
    Copy
    + Ord
    + From<i32>
    + core::ops::Add<Output = Self>
    + core::ops::Sub<Output = Self>
    + core::ops::Mul<Output = Self>
{
    /// `floor(self / d)` for `d > 0`.
    fn div_floor(self, d: Self) -> Self;
    /// The low 32 bits.
    fn low(self) -> i32;
    /// The low 32 bits of `self + s k`.
    fn low_plus(self, s: i32, k: Self) -> i32 {
        self.low().wrapping_add(s.wrapping_mul(k.low()))
    }
}

impl RowInt for i32 {
    #[inline(always)]
    fn div_floor(self, d: i32) -> i32 {
        crate::numeric::div_floor_i32(self, d)
    }
    #[inline(always)]
    fn low(self) -> i32 {
        self
    }
}

impl RowInt for i64 {
    /// By a 32-bit division when both fit `i32` (one instruction on a
    /// chip with a divider, where the `i64` one is a library call of
    /// about a hundred), else in `i64`.
    #[inline]
    fn div_floor(self, d: i64) -> i64 {
        match (i32::try_from(self), i32::try_from(d)) {
            (Ok(n), Ok(d)) => crate::numeric::div_floor_i32(n, d) as i64,
            _ => self.div_euclid(d),
        }
    }
    #[inline(always)]
    fn low(self) -> i32 {
        self as i32
    }
}

/// Whether a slice's rows can be solved in `i32`: every coordinate at the
/// anchor column of its rows and every step below `2^28` in magnitude
/// (then `b`, `top - b`, the quotients and `k` bounds stay below `2^30`;
/// voxel coordinates stay below `2^26`, [`super::MAX_VOLUME_SIDE`]).
fn narrow(t0: [i32; 3], tx: [i32; 3], ty: [i32; 3], bounds: Rect) -> bool {
    const LIM: i64 = 1 << 28;
    let last = bounds.h.saturating_sub(1) as i64;
    (0..3).all(|i| {
        let (a, b) = (t0[i] as i64, t0[i] as i64 + ty[i] as i64 * last);
        a.abs() < LIM && b.abs() < LIM && (tx[i] as i64).abs() < LIM
    }) && bounds.w < 1 << 15
        && bounds.x.unsigned_abs() < 1 << 28
}

/// A 3x3 matrix inverse by the adjugate; `None` when singular or not
/// finite.
fn inverse3<S: Real>(m: &[[S; 3]; 3]) -> Option<[[S; 3]; 3]> {
    let c =
        |r0: usize, c0: usize, r1: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let adj = [
        [c(1, 1, 2, 2), -c(0, 1, 2, 2), c(0, 1, 1, 2)],
        [-c(1, 0, 2, 2), c(0, 0, 2, 2), -c(0, 0, 1, 2)],
        [c(1, 0, 2, 1), -c(0, 0, 2, 1), c(0, 0, 1, 1)],
    ];
    let det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0];
    if det == S::ZERO || !det.is_finite() {
        return None;
    }
    let inv = S::ONE.div(det);
    let out = adj.map(|r| r.map(|v| v * inv));
    out.iter().flatten().all(|v| v.is_finite()).then_some(out)
}

/// The matrix from 16.16-free voxel coordinates (`0..dims - 1` per axis)
/// to the volume's model space: the box centred on the origin, its longest
/// physical side 1 long.
pub(crate) fn voxel_to_model<S: Real>(vol: &Volume<'_>) -> Mat4<S> {
    let (d, sp) = (vol.dims(), vol.spacing());
    let ext = |a: usize| (d[a] as i64 - 1) * sp[a] as i64;
    let long = ext(0).max(ext(1)).max(ext(2));
    let mut m = Mat4::IDENTITY;
    for a in 0..3 {
        // s = spacing / longest side (<= 1), 16 fraction bits.
        let s = S::from_q(((sp[a] as i64) << 16) / long, 16);
        m.m[a][a] = s;
        m.m[a][3] = -(S::from_q(d[a] as i64 - 1, 1) * s);
    }
    m
}

/// Sets up `count` view-aligned slices of `vol` placed by `model` (its box
/// centred on the origin, longest side 1: [`voxel_to_model`]), seen through
/// `view` and `proj` on `viewport` (pixels), farthest first, into `out`.
/// Slices behind the camera, outside the depth range `[0, 1]` or off the
/// viewport are left out. [`Error::Degenerate`] for a singular or
/// non-finite model-view, a projection whose `w` depends on `x` or `y`, or
/// an empty viewport; [`Error::ListFull`] when `out` is full.
pub(crate) fn slice<S: Real, const K: usize>(
    vol: &Volume<'_>,
    model: &Mat4<S>,
    view: &Mat4<S>,
    proj: &Mat4<S>,
    viewport: Rect,
    count: u16,
    out: &mut heapless::Vec<Slice, K>,
) -> Result<(), Error> {
    let p = &proj.m;
    if p[3][0] != S::ZERO || p[3][1] != S::ZERO || viewport.w == 0 || viewport.h == 0 || count == 0
    {
        return Err(Error::Degenerate);
    }
    let g = view.mul(model).mul(&voxel_to_model::<S>(vol));
    if !g.is_finite() || !proj.is_finite() {
        return Err(Error::Degenerate);
    }
    let a3 = [0, 1, 2].map(|r| [g.m[r][0], g.m[r][1], g.m[r][2]]);
    let ai = inverse3(&a3).ok_or(Error::Degenerate)?;
    let dims = vol.dims();
    let corner = |k: usize| {
        let c = |a: usize| {
            S::from_i32(if k >> a & 1 == 1 {
                dims[a] as i32 - 1
            } else {
                0
            })
        };
        g.transform([c(0), c(1), c(2)])
    };
    let eye: [[S; 4]; 8] = core::array::from_fn(corner);
    let (mut zmin, mut zmax) = (eye[0][2], eye[0][2]);
    for e in &eye {
        zmin = zmin.min(e[2]);
        zmax = zmax.max(e[2]);
    }
    let (hw, hh) = (
        S::from_q(viewport.w as i64, 1),
        S::from_q(viewport.h as i64, 1),
    );
    let cx = S::from_q(2 * viewport.x as i64 + viewport.w as i64, 1);
    let cy = S::from_q(2 * viewport.y as i64 + viewport.h as i64, 1);
    let n = S::from_i32(count as i32);
    let dz = (zmax - zmin).div(n);
    const EDGES: [(usize, usize); 12] = [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    for k in 0..count {
        // Farthest first: the camera looks down -z.
        let c = zmin + dz * (S::from_i32(k as i32) + S::HALF);
        let w = p[3][2] * c + p[3][3];
        // Behind the camera, or not a number.
        if w.partial_cmp(&S::ZERO) != Some(core::cmp::Ordering::Greater) {
            continue;
        }
        let iw = S::ONE.div(w);
        let ndc_z = (p[2][2] * c + p[2][3]) * iw;
        if ndc_z < S::ZERO || ndc_z > S::ONE || !ndc_z.is_finite() {
            continue;
        }
        let z = (ndc_z * S::from_q(65535, 16))
            .to_fixed(16)
            .ok_or(Error::Degenerate)?;
        let (a, b) = (hw * iw, hh * iw);
        let k0 = p[0][2] * c + p[0][3];
        let k1 = p[1][2] * c + p[1][3];
        let screen = |x: S, y: S| {
            (
                cx + a * (p[0][0] * x + p[0][1] * y + k0),
                cy - b * (p[1][0] * x + p[1][1] * y + k1),
            )
        };
        // The polygon's corners (plane x box edges), for the bounds.
        let (mut lo, mut hi) = ((S::ZERO, S::ZERO), (S::ZERO, S::ZERO));
        let mut any = false;
        for (i, j) in EDGES {
            let (e0, e1) = (eye[i], eye[j]);
            let (d0, d1) = (e0[2] - c, e1[2] - c);
            if (d0 > S::ZERO && d1 > S::ZERO) || (d0 < S::ZERO && d1 < S::ZERO) || d0 == d1 {
                continue;
            }
            let f = d0.div(d0 - d1);
            let (sx, sy) = screen(e0[0] + (e1[0] - e0[0]) * f, e0[1] + (e1[1] - e0[1]) * f);
            if !any {
                (lo, hi, any) = ((sx, sy), (sx, sy), true);
            }
            lo = (lo.0.min(sx), lo.1.min(sy));
            hi = (hi.0.max(sx), hi.1.max(sy));
        }
        if !any {
            continue;
        }
        // Pixels whose centres can be inside, one pixel of margin, cut to
        // the viewport.
        // (In i64, cut to the viewport before it is a `Rect`: a corner
        // near the camera plane projects anywhere in `i32`.)
        let px = |v: S| {
            (v - S::HALF)
                .to_fixed(0)
                .map(i64::from)
                .ok_or(Error::Degenerate)
        };
        let (vx0, vy0) = (viewport.x as i64, viewport.y as i64);
        let (vx1, vy1) = (vx0 + viewport.w as i64, vy0 + viewport.h as i64);
        let (x0, y0) = ((px(lo.0)? - 1).max(vx0), (px(lo.1)? - 1).max(vy0));
        let (x1, y1) = ((px(hi.0)? + 2).min(vx1), (px(hi.1)? + 2).min(vy1));
        if x0 >= x1 || y0 >= y1 {
            continue;
        }
        let bounds = Rect::new(x0 as i32, y0 as i32, (x1 - x0) as u32, (y1 - y0) as u32);
        // Screen to eye on the plane: invert the 2x2 of (x, y) -> screen.
        let m = [[a * p[0][0], a * p[0][1]], [-(b * p[1][0]), -(b * p[1][1])]];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        if det == S::ZERO {
            continue;
        }
        let id = S::ONE.div(det);
        let (exx, exy) = (m[1][1] * id, -(m[0][1] * id));
        let (eyx, eyy) = (-(m[1][0] * id), m[0][0] * id);
        // Screen point of eye (0, 0, c): (u0, v0).
        let (u0, v0) = (cx + a * k0, cy - b * k1);
        let (ax, ay) = (
            S::from_i32(bounds.x) + S::HALF - u0,
            S::from_i32(bounds.y) + S::HALF - v0,
        );
        let e = [
            exx * ax + exy * ay - g.m[0][3],
            eyx * ax + eyy * ay - g.m[1][3],
            c - g.m[2][3],
        ];
        let mulv =
            |v: [S; 3]| [0, 1, 2].map(|r| ai[r][0] * v[0] + ai[r][1] * v[1] + ai[r][2] * v[2]);
        let fx = |v: [S; 3]| -> Result<[i32; 3], Error> {
            let t = mulv(v);
            Ok([
                t[0].to_fixed(16).ok_or(Error::Degenerate)?,
                t[1].to_fixed(16).ok_or(Error::Degenerate)?,
                t[2].to_fixed(16).ok_or(Error::Degenerate)?,
            ])
        };
        let (t0, tx, ty) = (fx(e)?, fx([exx, eyx, S::ZERO])?, fx([exy, eyy, S::ZERO])?);
        let slice = Slice {
            z: z.clamp(0, 65535) as u16,
            bounds,
            t0,
            tx,
            ty,
            narrow: narrow(t0, tx, ty, bounds),
        };
        out.push(slice).map_err(|_| Error::ListFull)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `i32` solve equals the `i64` one on every row of random narrow
    /// slices, across the `2^28` limits' neighbourhood and with zero
    /// steps; `narrow` refuses slices whose rows would not fit.
    #[test]
    fn narrow_rows_equal_wide_rows() {
        let mut next = crate::numeric::xorshift(31);
        let mut tried = 0;
        for k in 0..3000 {
            let scale = [1 << 12, 1 << 18, 1 << 24, (1 << 28) / 70][k % 4];
            let mut r = || (next() as i32 as i64 % scale) as i32;
            let bounds = Rect::new(r() % 50, r() % 50, 1 + (r().unsigned_abs() % 64), 64);
            let (t0, mut tx, ty) = (
                [r(), r(), r()],
                [r(), r(), r()],
                [r() / 8, r() / 8, r() / 8],
            );
            if k % 7 == 0 {
                tx[k % 3] = 0;
            }
            let top = [9 << 16, 31 << 16, 1023 << 16];
            // The whole box, or a box of visible cells inside it.
            let bot = [[0; 3], [1 << 16, 0, 7 << 16]][k % 2];
            let mut s = Slice {
                z: 0,
                bounds,
                t0,
                tx,
                ty,
                narrow: narrow(t0, tx, ty, bounds),
            };
            if !s.narrow {
                continue;
            }
            tried += 1;
            for py in bounds.y..bounds.y + bounds.h as i32 {
                let (lo, hi) = (bounds.x, bounds.x + bounds.w as i32);
                let got = s.row(py, lo, hi, [bot, top]);
                s.narrow = false;
                let want = s.row(py, lo, hi, [bot, top]);
                s.narrow = true;
                if want.0 < want.1 {
                    assert_eq!(got, want, "{s:?} row {py}");
                } else {
                    assert!(got.0 >= got.1, "{s:?} row {py}");
                }
            }
        }
        assert!(tried > 1000, "{tried}");
        let big = Slice {
            z: 0,
            bounds: Rect::new(0, 0, 8, 8),
            t0: [1 << 29, 0, 0],
            tx: [1; 3],
            ty: [0; 3],
            narrow: false,
        };
        assert!(!narrow(big.t0, big.tx, big.ty, big.bounds));
        assert!(!narrow([0; 3], [0; 3], [1 << 26, 0, 0], big.bounds));
    }
}
