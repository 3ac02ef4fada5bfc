//! Vectors and 4x4 matrices over a [`Real`] back end: model transforms
//! (rotate, translate, scale, compose), the camera's look-at, and
//! perspective and orthographic projections.
//!
//! Conventions (OpenGL's, with Direct3D's depth range): right-handed world,
//! the camera looks down its `-z`; clip space keeps `x, y` in `[-w, w]` and
//! depth `z` in `[0, w]`, `0` at the near plane — the rasterizer's "0 is
//! nearest" 16-bit Z after the divide. Matrices act on column vectors:
//! `a.mul(&b)` applies `b` first.

use super::real::{above, Angle, Real};
use crate::error::Error;

/// A 3-vector.
pub type Vec3<S> = [S; 3];

/// The dot product.
pub fn dot<S: Real>(a: Vec3<S>, b: Vec3<S>) -> S {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The cross product.
pub fn cross<S: Real>(a: Vec3<S>, b: Vec3<S>) -> Vec3<S> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a - b`.
pub fn sub<S: Real>(a: Vec3<S>, b: Vec3<S>) -> Vec3<S> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a` scaled to unit length; [`Error::Degenerate`] for a zero or
/// non-finite vector.
pub fn normalize<S: Real>(a: Vec3<S>) -> Result<Vec3<S>, Error> {
    let k = dot(a, a).inv_sqrt();
    let n = [a[0] * k, a[1] * k, a[2] * k];
    if n.iter().all(|v| v.is_finite()) && k.is_finite() {
        Ok(n)
    } else {
        Err(Error::Degenerate)
    }
}

/// A 4x4 matrix, `m[row][column]`.
///
/// ```
/// use tilerast::geometry::{Angle, Mat4};
/// let m = Mat4::<f32>::translation([1.0, 2.0, 3.0]).mul(&Mat4::rotation_z(Angle::degrees(90)));
/// let p = m.transform([1.0, 0.0, 0.0]);
/// assert!((p[0] - 1.0).abs() < 1e-6 && (p[1] - 3.0).abs() < 1e-6 && p[3] == 1.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mat4<S> {
    /// Rows of columns.
    pub m: [[S; 4]; 4],
}

impl<S: Real> Default for Mat4<S> {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl<S: Real> Mat4<S> {
    /// The identity.
    pub const IDENTITY: Self = {
        let (o, z) = (S::ONE, S::ZERO);
        Mat4 {
            m: [[o, z, z, z], [z, o, z, z], [z, z, o, z], [z, z, z, o]],
        }
    };

    /// `self * o`: `o` is applied first.
    pub fn mul(&self, o: &Self) -> Self {
        let mut m = [[S::ZERO; 4]; 4];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = self.m[r][0] * o.m[0][c]
                    + self.m[r][1] * o.m[1][c]
                    + self.m[r][2] * o.m[2][c]
                    + self.m[r][3] * o.m[3][c];
            }
        }
        Mat4 { m }
    }

    /// The homogeneous image `(x, y, z, w)` of point `p`.
    #[inline]
    pub fn transform(&self, p: Vec3<S>) -> [S; 4] {
        let m = &self.m;
        let row = |r: usize| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3];
        [row(0), row(1), row(2), row(3)]
    }

    /// The image of direction `d` under the upper-left 3x3 (no translation).
    pub fn transform_dir(&self, d: Vec3<S>) -> Vec3<S> {
        let m = &self.m;
        let row = |r: usize| m[r][0] * d[0] + m[r][1] * d[1] + m[r][2] * d[2];
        [row(0), row(1), row(2)]
    }

    /// The image of `d` under the *transposed* upper-left 3x3: for a
    /// rotation, the inverse (world light directions to model space).
    pub fn transform_dir_transposed(&self, d: Vec3<S>) -> Vec3<S> {
        let m = &self.m;
        let col = |c: usize| m[0][c] * d[0] + m[1][c] * d[1] + m[2][c] * d[2];
        [col(0), col(1), col(2)]
    }

    /// Every entry finite (see [`Real::is_finite`]).
    pub fn is_finite(&self) -> bool {
        self.m.iter().flatten().all(|v| v.is_finite())
    }

    /// Translation by `t`.
    pub fn translation(t: Vec3<S>) -> Self {
        let mut m = Self::IDENTITY;
        m.m[0][3] = t[0];
        m.m[1][3] = t[1];
        m.m[2][3] = t[2];
        m
    }

    /// Scaling by `s` per axis. Lighting is exact for uniform scales;
    /// under a non-uniform one, normals are not re-normalised per vertex.
    pub fn scale(s: Vec3<S>) -> Self {
        let mut m = Self::IDENTITY;
        m.m[0][0] = s[0];
        m.m[1][1] = s[1];
        m.m[2][2] = s[2];
        m
    }

    fn rotation(a: Angle, i: usize, j: usize) -> Self {
        let (s, c) = a.sin_cos::<S>();
        let mut m = Self::IDENTITY;
        m.m[i][i] = c;
        m.m[i][j] = -s;
        m.m[j][i] = s;
        m.m[j][j] = c;
        m
    }

    /// Rotation about `x` (counter-clockwise looking down the axis).
    pub fn rotation_x(a: Angle) -> Self {
        Self::rotation(a, 1, 2)
    }
    /// Rotation about `y`.
    pub fn rotation_y(a: Angle) -> Self {
        Self::rotation(a, 2, 0)
    }
    /// Rotation about `z`.
    pub fn rotation_z(a: Angle) -> Self {
        Self::rotation(a, 0, 1)
    }

    /// The view matrix of a camera at `eye` looking at `target`, `up`
    /// roughly up. [`Error::Degenerate`] when `eye == target` or `up` is
    /// parallel to the view direction.
    ///
    /// ```
    /// use tilerast::geometry::Mat4;
    /// let v = Mat4::<f32>::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])?;
    /// let o = v.transform([0.0; 3]); // the target, 3 units in front
    /// assert!(o[0].abs() < 1e-6 && o[1].abs() < 1e-6 && (o[2] + 3.0).abs() < 1e-6);
    /// assert!(Mat4::<f32>::look_at([0.0; 3], [0.0; 3], [0.0, 1.0, 0.0]).is_err());
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn look_at(eye: Vec3<S>, target: Vec3<S>, up: Vec3<S>) -> Result<Self, Error> {
        let f = normalize(sub(target, eye))?;
        let r = normalize(cross(f, up))?;
        let u = cross(r, f);
        let z = S::ZERO;
        Ok(Mat4 {
            m: [
                [r[0], r[1], r[2], -dot(r, eye)],
                [u[0], u[1], u[2], -dot(u, eye)],
                [-f[0], -f[1], -f[2], dot(f, eye)],
                [z, z, z, S::ONE],
            ],
        })
    }

    /// A perspective projection: vertical field of view `fov_y`, `aspect`
    /// = width / height, clip planes at distances `near < far`. Depth maps
    /// to `0` at `near` and `w` at `far`, hyperbolically, like OpenGL's
    /// window z. [`Error::Degenerate`] for a field of view of 0 or 180° and
    /// more, `near <= 0`, `far <= near` or a non-positive aspect.
    ///
    /// ```
    /// use tilerast::geometry::{Angle, Mat4};
    /// let p = Mat4::<f32>::perspective(Angle::degrees(90), 1.0, 1.0, 5.0)?;
    /// let near = p.transform([0.0, 0.0, -1.0]);
    /// let far = p.transform([0.0, 0.0, -5.0]);
    /// assert!(near[2].abs() < 1e-6 && (far[2] - far[3]).abs() < 1e-5);
    /// assert!(Mat4::<f32>::perspective(Angle::degrees(0), 1.0, 1.0, 5.0).is_err());
    /// # Ok::<(), tilerast::Error>(())
    /// ```
    pub fn perspective(fov_y: Angle, aspect: S, near: S, far: S) -> Result<Self, Error> {
        let q = fov_y.turn_q16();
        if q == 0
            || q >= 32768
            || !above(near, S::ZERO)
            || !above(far, near)
            || !above(aspect, S::ZERO)
        {
            return Err(Error::Degenerate);
        }
        let (s, c) = Angle::from_turn_q16(q / 2).sin_cos::<S>();
        let f = c.div(s);
        let nf = near - far;
        let z = S::ZERO;
        let m = Mat4 {
            m: [
                [f.div(aspect), z, z, z],
                [z, f, z, z],
                [z, z, far.div(nf), (near * far).div(nf)],
                [z, z, -S::ONE, z],
            ],
        };
        m.checked()
    }

    /// An orthographic projection of the box `[l, r] x [b, t]`, depths
    /// `near..far` in front of the camera, to `x, y` in `[-1, 1]` and depth
    /// in `[0, 1]`. [`Error::Degenerate`] for an empty box.
    pub fn orthographic(l: S, r: S, b: S, t: S, near: S, far: S) -> Result<Self, Error> {
        if !above(r, l) || !above(t, b) || !above(far, near) {
            return Err(Error::Degenerate);
        }
        let two = S::ONE + S::ONE;
        let (w, h, d) = (r - l, t - b, far - near);
        let z = S::ZERO;
        let m = Mat4 {
            m: [
                [two.div(w), z, z, -(r + l).div(w)],
                [z, two.div(h), z, -(t + b).div(h)],
                [z, z, -S::ONE.div(d), -near.div(d)],
                [z, z, z, S::ONE],
            ],
        };
        m.checked()
    }

    fn checked(self) -> Result<Self, Error> {
        if self.is_finite() {
            Ok(self)
        } else {
            Err(Error::Degenerate)
        }
    }
}
