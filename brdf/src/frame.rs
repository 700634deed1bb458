//! The shading frame: an orthonormal basis around a unit normal, in which the BSDFs work
//! (z = normal, `wo`/`wi` in local coordinates).

use glam::Vec3;

/// An orthonormal frame around a unit normal (Duff et al., "Building an Orthonormal Basis,
/// Revisited", JCGT 2017): branch-free, continuous except across `n.z = 0`'s sign, and exact
/// at the poles. `z` is the normal; the basis is right-handed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub x: Vec3,
    /// Second tangent.
    pub y: Vec3,
    /// The normal.
    pub z: Vec3,
}

impl Frame {
    /// The frame of unit normal `n`. `n.z = −0.0` is treated as negative (the sign bit decides,
    /// as `copysign` does; the WGSL twin reads the same bit).
    pub fn new(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { x, y, z: n }
    }

    /// The frame of unit normal `n` whose x axis is `tangent` made orthogonal to `n` (an
    /// anisotropic lobe's direction); `y = n × x`. [`Frame::new`]'s where `tangent` is within
    /// ~0.06° of `n` (or zero, or not finite): there its part across `n` is mostly rounding.
    /// The part across is projected twice ("twice is enough", Parlett): once, a tangent near
    /// `n` leaves x off orthogonal by the rounding of `n·t` over that part's length.
    pub fn with_tangent(n: Vec3, tangent: Vec3) -> Self {
        let across = tangent - n * n.dot(tangent);
        if !(across.length_squared() > 1e-6 * tangent.length_squared()) {
            return Self::new(n);
        }
        let across = across - n * n.dot(across);
        let x = across.normalize();
        Self { x, y: n.cross(x), z: n }
    }

    /// World → local: the components along `x`, `y`, `z`.
    pub fn to_local(self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    /// Local → world.
    pub fn to_world(self, v: Vec3) -> Vec3 {
        v.x * self.x + v.y * self.y + v.z * self.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_round_trips() {
        // Tolerance: a few f32 ulps of unit-length arithmetic.
        for n in
            [Vec3::Z, Vec3::NEG_Z, Vec3::X, Vec3::new(0.3, -0.5, 0.2).normalize(), Vec3::new(1e-8, 0.0, -1.0)]
        {
            let n = n.normalize();
            let f = Frame::new(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5 && (f.y.length() - 1.0).abs() < 1e-5);
            assert!(f.x.dot(f.y).abs() < 1e-5 && f.x.dot(n).abs() < 1e-5 && f.y.dot(n).abs() < 1e-5);
            assert!(f.x.cross(f.y).dot(n) > 0.99, "right-handed");
            let v = Vec3::new(0.1, 0.7, -0.2);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn frame_with_tangent_puts_x_along_it() {
        // Tolerance: a few f32 ulps, as above.
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let t = Vec3::new(1.0, 0.2, 0.1); // not orthogonal to n, not unit
        let f = Frame::with_tangent(n, t);
        let expected = (t - n * n.dot(t)).normalize();
        assert!((f.x - expected).length() < 1e-5);
        assert!(f.x.dot(n).abs() < 1e-5 && f.y.dot(n).abs() < 1e-5 && f.x.dot(f.y).abs() < 1e-5);
        assert!((f.x.cross(f.y) - n).length() < 1e-5, "right-handed");
        // A tangent along the normal gives the plain frame.
        assert_eq!(Frame::with_tangent(n, 2.0 * n), Frame::new(n));
    }
}
