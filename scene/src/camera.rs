//! Cameras and primary rays, following the reference renders' convention
//! (`tests/data/references/README.md`): the camera looks down its node's −Z with +Y up; pixel
//! `(i, j)` covers `[i, i+1] × [j, j+1]` with row 0 at the **top**; `yfov` is vertical.

use glam::{Affine3A, Vec2, Vec3};

/// A ray: origin and unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin (world space).
    pub origin: Vec3,
    /// Unit direction (world space).
    pub direction: Vec3,
}

/// How the camera projects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Pinhole camera.
    Perspective {
        /// Vertical field of view in radians (glTF `yfov`).
        yfov: f32,
        /// The file's `aspectRatio`, informative only: rays use the image's `width/height`, so
        /// the vertical field of view is kept whatever the image shape (what Mitsuba does too).
        aspect_ratio: Option<f32>,
    },
    /// Parallel projection.
    Orthographic {
        /// Half width of the view (glTF `xmag`), informative only: rays use `ymag × width/height`.
        xmag: f32,
        /// Half height of the view (glTF `ymag`).
        ymag: f32,
    },
}

/// A camera: where it is and how it projects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Camera-to-world transform (rotation and translation; any scale in the node is removed).
    pub world_from_camera: Affine3A,
    /// The projection.
    pub projection: Projection,
}

/// The vertical field of view of the camera framed around a scene without one: 45°.
pub const DEFAULT_YFOV: f32 = std::f32::consts::FRAC_PI_4;

impl Camera {
    /// A perspective camera at `eye` looking at `target` with `up` (+Y if degenerate).
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Self {
        let mut forward = (target - eye).normalize_or_zero();
        if forward == Vec3::ZERO {
            forward = Vec3::NEG_Z;
        }
        let mut right = forward.cross(up).normalize_or_zero();
        if right == Vec3::ZERO {
            right = forward.any_orthonormal_vector();
        }
        let up = right.cross(forward);
        let rot = glam::Mat3::from_cols(right, up, -forward);
        Self {
            world_from_camera: Affine3A::from_mat3_translation(rot, eye),
            projection: Projection::Perspective { yfov, aspect_ratio: None },
        }
    }

    /// The default camera for a scene with no camera: looks along −Z at the centre of the
    /// bounds `[min, max]` from the +Z side, with [`DEFAULT_YFOV`], far enough that the bounding
    /// sphere fits in the vertical field of view (distance `r / sin(yfov/2)`). A flat asset
    /// (bounds thinner than [`FLAT_THICKNESS`] of their size along x or y: a ground plane, a wall facing
    /// ±x), which −Z would see edge-on as an empty frame, is seen from 45° between its normal and
    /// +Z.
    pub fn frame_bounds(min: Vec3, max: Vec3) -> Self {
        let center = (min + max) * 0.5;
        let r = ((max - min).length() * 0.5).max(1e-3);
        let d = r / (DEFAULT_YFOV * 0.5).sin();
        let size = (max - min).max_element();
        let thin = |e: f32| e <= FLAT_THICKNESS * size;
        let extent = max - min;
        let from = if thin(extent.y) && !thin(extent.z) {
            Vec3::new(0.0, 1.0, 1.0).normalize()
        } else if thin(extent.x) && !thin(extent.z) {
            Vec3::new(1.0, 0.0, 1.0).normalize()
        } else {
            Vec3::Z
        };
        Self::look_at(center + from * d, center, Vec3::Y, DEFAULT_YFOV)
    }

    /// The ray through the film point `pixel` (in pixels, jitter included: pixel `(i, j)` is
    /// `[i, i+1] × [j, j+1]`, row 0 at the top) of a `width × height` image.
    pub fn generate_ray(&self, pixel: Vec2, width: u32, height: u32) -> Ray {
        self.rays(width, height).generate(pixel)
    }

    /// [`Camera::generate_ray`] for a `width × height` image with the per-image constants
    /// (the field of view's tangent, the aspect ratio) formed once: a renderer generating
    /// every pixel's rays keeps one. The rays are the same to the bit.
    pub fn rays(&self, width: u32, height: u32) -> CameraRays {
        let (w, h) = (width.max(1) as f32, height.max(1) as f32);
        let aspect = w / h;
        let scale = match self.projection {
            Projection::Perspective { yfov, .. } => (yfov * 0.5).tan(),
            Projection::Orthographic { ymag, .. } => ymag,
        };
        CameraRays { camera: *self, w, h, aspect, scale }
    }
}

/// The thickness, relative to its largest extent, below which [`Camera::frame_bounds`] takes
/// an asset for flat.
pub const FLAT_THICKNESS: f32 = 0.01;

/// A [`Camera`] with the constants of one image size formed: [`Camera::rays`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraRays {
    camera: Camera,
    w: f32,
    h: f32,
    aspect: f32,
    /// `tan(yfov / 2)` (perspective) or `ymag` (orthographic).
    scale: f32,
}

impl CameraRays {
    /// The ray through the film point `pixel`, as [`Camera::generate_ray`].
    #[inline]
    pub fn generate(&self, pixel: Vec2) -> Ray {
        let (w, h, t, aspect) = (self.w, self.h, self.scale, self.aspect);
        // Normalised device coordinates: x right in [−1, 1], y up in [−1, 1].
        let x = 2.0 * pixel.x / w - 1.0;
        let y = 1.0 - 2.0 * pixel.y / h;
        let (o, d) = match self.camera.projection {
            Projection::Perspective { .. } => (Vec3::ZERO, Vec3::new(x * t * aspect, y * t, -1.0)),
            Projection::Orthographic { .. } => (Vec3::new(x * t * aspect, y * t, 0.0), Vec3::NEG_Z),
        };
        Ray {
            origin: self.camera.world_from_camera.transform_point3(o),
            direction: self.camera.world_from_camera.transform_vector3(d).normalize(),
        }
    }
}

#[cfg(test)]
mod tests {

    /// A flat asset is framed from an angle: the centre ray of a ground plane (y = 0) or a wall
    /// facing x hits it inside its bounds, where looking along −Z would graze it; bounds that
    /// are not flat keep the view along −Z.
    #[test]
    fn flat_assets_are_framed_from_an_angle() {
        let hits = |min: Vec3, max: Vec3, axis: usize| {
            let ray = Camera::frame_bounds(min, max).generate_ray(Vec2::new(32.0, 32.0), 64, 64);
            let t = (min[axis] - ray.origin[axis]) / ray.direction[axis];
            let p = ray.origin + t * ray.direction;
            // At the plane, within the bounds (f32 rounding of a unit-size scene: 1e-5).
            t > 0.0 && (p - p.clamp(min, max)).abs().max_element() < 1e-5
        };
        let ground = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0));
        assert!(hits(ground.0, ground.1, 1), "a ground plane");
        let wall = (Vec3::new(2.0, -1.0, -1.0), Vec3::new(2.0, 1.0, 1.0));
        assert!(hits(wall.0, wall.1, 0), "a wall facing x");
        let facing = (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
        assert!(hits(facing.0, facing.1, 2), "a plane facing the default view");
        // Not flat: the view along −Z, eye on +Z.
        let c = Camera::frame_bounds(Vec3::splat(-1.0), Vec3::ONE);
        let eye = c.world_from_camera.translation;
        assert!(eye.x == 0.0 && eye.y == 0.0 && eye.z > 0.0, "{eye}");
    }

    use super::*;

    #[test]
    fn centre_ray_looks_down_minus_z_and_row_zero_is_top() {
        let cam = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, DEFAULT_YFOV);
        let r = cam.generate_ray(Vec2::new(50.0, 50.0), 100, 100);
        // Tolerance: f32 rounding of the look-at basis.
        assert!((r.direction - Vec3::NEG_Z).length() < 1e-6);
        let top = cam.generate_ray(Vec2::new(50.0, 0.0), 100, 100);
        assert!(top.direction.y > 0.0);
        // The top edge is at yfov/2 above the axis.
        let angle = top.direction.angle_between(Vec3::NEG_Z);
        assert!((angle - DEFAULT_YFOV / 2.0).abs() < 1e-5);
        let right = cam.generate_ray(Vec2::new(100.0, 50.0), 100, 100);
        assert!(right.direction.x > 0.0);
    }

    #[test]
    fn framing_contains_the_bounds() {
        let cam = Camera::frame_bounds(Vec3::splat(-1.0), Vec3::splat(1.0));
        let eye = cam.world_from_camera.translation;
        // Every corner lies within the vertical half-angle.
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            let a = (c - Vec3::from(eye)).angle_between(Vec3::NEG_Z);
            assert!(a <= DEFAULT_YFOV / 2.0 + 1e-5);
        }
    }
}
