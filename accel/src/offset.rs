//! Robust ray-origin offsets: Wächter & Binder, "A Fast and Robust Method for Avoiding
//! Self-Intersection", *Ray Tracing Gems* (2019), chapter 6.
//!
//! A hit point computed in `f32` lies off its triangle's plane by up to a few ULPs of its
//! coordinates, on either side. A secondary ray started there may hit its own triangle again
//! ("shadow acne"). A fixed epsilon (the thesis used `p + 1e-3 · n`) is too small once the
//! coordinates are large (at |p| = 1e5 one ULP is 0.0078, so adding 1e-3 does nothing) and far
//! too large when the scene is small (at a 1e-3 scale it jumps over whole objects). Wächter &
//! Binder instead move the point by a fixed number of **ULPs** along the normal, done in integer
//! arithmetic on the bit pattern, which scales with the coordinate's own precision; close to the
//! origin, where ULPs become tiny (and subnormal), a small fixed float offset takes over.
//!
//! That float offset (2⁻¹⁶ below |p| = 1/32) assumes a scene of about unit size: in a scene
//! 1e-4 across it is a sixth of the scene and light leaks through corners (measured:
//! `tests/tests/stability.rs`). [`offset_ray_origin_scaled`] multiplies both constants by the
//! scene's [`offset_scale`] — the power of two at or above its extent, at most 1 — so a scene
//! scaled by a power of two gets exactly scaled offsets, and scenes of unit size or more keep
//! the paper's constants bit for bit.

use glam::Vec3;

/// Below this magnitude a coordinate is offset by a float step instead of an integer one
/// (the paper's `origin()` constant, 1/32).
pub const ORIGIN: f32 = 1.0 / 32.0;
/// Float step used for coordinates below [`ORIGIN`] (the paper's `float_scale()`, 1/65536).
pub const FLOAT_SCALE: f32 = 1.0 / 65536.0;
/// ULPs moved per unit of normal component (the paper's `int_scale()`, 256).
pub const INT_SCALE: f32 = 256.0;

/// Offsets a surface point `p` along the geometric normal `n` so that a ray started there does
/// not hit the surface it leaves (Wächter & Binder 2019, listing 6-1).
///
/// `n` must point to the side the new ray leaves to: for a ray leaving through the back of a
/// triangle, pass the negated normal. It need not be normalised, but its components are used as
/// weights of [`INT_SCALE`] ULPs, so a unit normal is intended. Each coordinate moves by
/// `256 · n_i` ULPs of itself, or by `n_i / 65536` where `|p_i| < 1/32`.
///
/// Non-finite input is returned unchanged (a NaN point stays NaN).
///
/// ```
/// use furnace_accel::offset_ray_origin;
/// use glam::Vec3;
/// let p = Vec3::new(1.0e5, 0.0, 0.5);
/// let q = offset_ray_origin(p, Vec3::X);
/// assert!(q.x > p.x);  // a fixed 1e-3 step would have been rounded away here
/// assert_eq!(q.y, p.y); // no normal component, no move
/// ```
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    offset_ray_origin_scaled(p, n, 1.0)
}

/// [`offset_ray_origin`] for a scene of length scale `scale` ([`offset_scale`] of its extent):
/// coordinates below `ORIGIN · scale` move by `FLOAT_SCALE · scale · n_i`; the others by
/// `256 · n_i` ULPs as before. `scale = 1` is exactly [`offset_ray_origin`].
///
/// ```
/// use furnace_accel::{offset_ray_origin_scaled, offset_scale};
/// use glam::Vec3;
/// // A scene 1e-4 across: the offset is a few hundred ULPs, not a sixth of the scene.
/// let s = offset_scale(1e-4);
/// let q = offset_ray_origin_scaled(Vec3::new(2e-6, 5e-5, 0.0), Vec3::Z, s);
/// assert!(q.z > 0.0 && q.z < 1e-8);
/// ```
#[inline]
pub fn offset_ray_origin_scaled(p: Vec3, n: Vec3, scale: f32) -> Vec3 {
    let (origin, float_scale) = (ORIGIN * scale, FLOAT_SCALE * scale);
    Vec3::new(
        offset_coord(p.x, n.x, origin, float_scale),
        offset_coord(p.y, n.y, origin, float_scale),
        offset_coord(p.z, n.z, origin, float_scale),
    )
}

/// The length scale of [`offset_ray_origin_scaled`] for a scene whose coordinates all lie within
/// `±extent`: the smallest power of two ≥ `extent`, at most 1 (larger scenes keep the paper's
/// constants: their coordinates above 1/32 take integer offsets anyway) and at least 2⁻¹⁰⁰ (so
/// the float step stays a normal float). Not finite or ≥ 1 → 1.
pub fn offset_scale(extent: f32) -> f32 {
    const MIN: f32 = 7.888609e-31; // 2^-100
    if !(extent < 1.0) {
        return 1.0;
    }
    if !(extent > MIN) {
        return MIN;
    }
    let pow = f32::from_bits(extent.to_bits() & 0x7f80_0000); // 2^floor(log2 extent)
    if pow == extent { pow } else { 2.0 * pow }
}

/// [`offset_scale`] of a scene within the bounding box `(lo, hi)`: of its largest coordinate
/// magnitude (what both integrators use).
pub fn offset_scale_of_bounds(lo: Vec3, hi: Vec3) -> f32 {
    offset_scale(lo.abs().max(hi.abs()).max_element())
}

#[inline]
fn offset_coord(p: f32, n: f32, origin: f32, float_scale: f32) -> f32 {
    if !p.is_finite() || !n.is_finite() {
        return p;
    }
    if p.abs() < origin {
        return p + float_scale * n;
    }
    // Integer offset in ULPs; `as i32` truncates toward zero like the paper's `int(...)`.
    let of_i = (INT_SCALE * n) as i32;
    // Moving the bit pattern of a negative float *up* makes it more negative, so the step's sign
    // follows p's sign: `p < 0 ? -of_i : of_i` in the paper.
    let step = if p < 0.0 { -of_i } else { of_i };
    let moved = f32::from_bits((p.to_bits() as i32).wrapping_add(step) as u32);
    // |p| ≥ 1/32 is far from 0 and from the infinities for any |step| ≤ 256, so `moved` stays a
    // finite float of p's sign, except that p within 256 ULPs of f32::MAX may round to +-inf.
    if moved.is_finite() { moved } else { p }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_scale_is_the_power_of_two_at_or_above_the_extent() {
        assert_eq!(offset_scale(1.0), 1.0);
        assert_eq!(offset_scale(250.0), 1.0);
        assert_eq!(offset_scale(f32::NAN), 1.0);
        assert_eq!(offset_scale(f32::INFINITY), 1.0);
        assert_eq!(offset_scale(0.5), 0.5);
        assert_eq!(offset_scale(0.6), 1.0);
        assert_eq!(offset_scale(1e-4), 1.0 / 8192.0);
        assert_eq!(offset_scale(0.0), 7.888609e-31);
        // Scaled by a power of two, offsets scale exactly.
        let (p, n) = (Vec3::new(0.01, -0.3, 0.02), Vec3::new(0.6, 0.0, -0.8));
        let k = 2f32.powi(-20);
        assert_eq!(offset_ray_origin_scaled(p * k, n, k) / k, offset_ray_origin_scaled(p, n, 1.0));
        assert_eq!(offset_ray_origin_scaled(p, n, 1.0), offset_ray_origin(p, n));
    }

    #[test]
    fn moves_along_the_normal_at_every_scale() {
        for &s in &[1e-6f32, 1e-3, 0.03, 1.0, 1e3, 1e5, 1e7, -1e-6, -1e-3, -1.0, -1e5] {
            let p = Vec3::splat(s);
            let n = Vec3::new(1.0, -1.0, 0.0).normalize();
            let q = offset_ray_origin(p, n);
            assert!(q.x > p.x && q.y < p.y && q.z == p.z, "s = {s}: {p} -> {q}");
        }
    }

    #[test]
    fn non_finite_is_left_alone() {
        let q = offset_ray_origin(Vec3::new(f32::NAN, f32::INFINITY, f32::MAX), Vec3::X);
        assert!(q.x.is_nan() && q.y == f32::INFINITY && q.z == f32::MAX);
    }
}
