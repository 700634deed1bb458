//! The viewer's camera: orbit, pan and dolly about a pivot, and a fly mode, from the scene's
//! camera. Pure maths (no window), so it is tested here.

use furnace_scene::{Camera, Projection};
use glam::{Quat, Vec3};

/// Degrees of orbit per pixel dragged.
pub const ORBIT_DEGREES_PER_PIXEL: f32 = 0.25;
/// The pivot distance shrinks by this factor per wheel step (grows by its inverse).
pub const DOLLY_PER_STEP: f32 = 0.9;
/// Fly speed: this fraction of the scene's size per second (×4 with Shift).
pub const FLY_SCENE_PER_SECOND: f32 = 0.25;
/// The view direction stays this many degrees away from straight up or down (the orbit would
/// flip over the pole).
const POLE_MARGIN_DEGREES: f32 = 1.0;

/// Where the camera is and what it looks at: a look-at pose with a fixed world up (+Y, glTF's),
/// the scene camera's projection, and whether it still is the scene camera it started from.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraRig {
    /// The eye.
    pub eye: Vec3,
    /// The pivot of orbit and dolly, on the view axis.
    pub target: Vec3,
    /// World up.
    pub up: Vec3,
    /// The projection (vertical field of view or orthographic extent).
    pub projection: Projection,
    /// The camera it started from, used as long as the user has not moved.
    start: Camera,
    /// The pose it started from (for [`CameraRig::reset`]).
    start_pose: (Vec3, Vec3),
    /// Whether the user moved it (then it is the look-at pose, not `start`).
    moved: bool,
    /// The scene's size (the diagonal of its bounds), for fly speed.
    scene_size: f32,
}

impl CameraRig {
    /// A rig starting at `camera` (a scene camera or the framed default), with the pivot at the
    /// distance of the scene's centre (`bounds`) along the view axis.
    pub fn new(camera: Camera, bounds: (Vec3, Vec3)) -> Self {
        let m = camera.world_from_camera;
        let eye = Vec3::from(m.translation);
        let forward = (-Vec3::from(m.matrix3.z_axis)).normalize_or(Vec3::NEG_Z);
        let (lo, hi) = bounds;
        let finite = lo.is_finite() && hi.is_finite();
        let center = if finite { (lo + hi) * 0.5 } else { eye + forward };
        let scene_size = if finite { (hi - lo).length().max(1e-6) } else { 1.0 };
        // The pivot: as far along the view axis as the scene's centre is from the eye.
        let distance = (center - eye).length().max(scene_size * 1e-3);
        let target = eye + forward * distance;
        Self {
            eye,
            target,
            up: Vec3::Y,
            projection: camera.projection,
            start: camera,
            start_pose: (eye, target),
            moved: false,
            scene_size,
        }
    }

    /// The camera to render: the starting one until moved, then the look-at pose. A moved
    /// perspective camera is exactly `Camera::look_at(eye, target, up, deg.to_radians())` with
    /// `deg` = [`CameraRig::yfov_degrees`]: what `furnace render --look-at … --yfov deg` builds,
    /// so that a saved view resumes bit for bit.
    pub fn camera(&self) -> Camera {
        if !self.moved {
            return self.start;
        }
        match self.projection {
            Projection::Perspective { yfov, .. } => {
                Camera::look_at(self.eye, self.target, self.up, yfov.to_degrees().to_radians())
            }
            Projection::Orthographic { .. } => {
                let mut c = Camera::look_at(self.eye, self.target, self.up, furnace_scene::DEFAULT_YFOV);
                c.projection = self.projection;
                c
            }
        }
    }

    /// Whether the user moved the camera away from the one it started at.
    pub fn moved(&self) -> bool {
        self.moved
    }

    /// Back to the starting camera.
    pub fn reset(&mut self) {
        (self.eye, self.target) = self.start_pose;
        self.moved = false;
    }

    /// The vertical field of view in degrees of a perspective camera.
    pub fn yfov_degrees(&self) -> Option<f32> {
        match self.projection {
            Projection::Perspective { yfov, .. } => Some(yfov.to_degrees()),
            Projection::Orthographic { .. } => None,
        }
    }

    fn forward(&self) -> Vec3 {
        (self.target - self.eye).normalize_or(Vec3::NEG_Z)
    }

    fn right(&self) -> Vec3 {
        self.forward().cross(self.up).normalize_or(Vec3::X)
    }

    /// Turns `dir` by `yaw` about world up and `pitch` about `right`, keeping it away from the
    /// poles.
    fn turn(&self, dir: Vec3, yaw: f32, pitch: f32) -> Vec3 {
        let right = dir.cross(self.up).normalize_or(Vec3::X);
        let margin = POLE_MARGIN_DEGREES.to_radians();
        // Angle of `dir` from up; a positive pitch about `right` lowers it. Kept within
        // [margin, π − margin] after the pitch.
        let from_up = dir.normalize_or(Vec3::NEG_Z).dot(self.up).clamp(-1.0, 1.0).acos();
        let pitch = pitch.clamp(from_up - (std::f32::consts::PI - margin), from_up - margin);
        let q = Quat::from_axis_angle(self.up, yaw) * Quat::from_axis_angle(right, pitch);
        q * dir
    }

    /// Orbits the eye about the pivot: `dx`, `dy` pixels dragged (right: the camera goes left
    /// round the pivot, the scene turns right; down: the camera goes up).
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        let k = ORBIT_DEGREES_PER_PIXEL.to_radians();
        let offset = self.eye - self.target;
        let turned = self.turn(offset, -dx * k, dy * k);
        self.eye = self.target + turned;
        self.moved = true;
    }

    /// Turns the view about the eye (fly mode's mouse look): `dx`, `dy` pixels dragged.
    pub fn look(&mut self, dx: f32, dy: f32) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        let k = ORBIT_DEGREES_PER_PIXEL.to_radians();
        let offset = self.target - self.eye;
        self.target = self.eye + self.turn(offset, -dx * k, -dy * k);
        self.moved = true;
    }

    /// Moves eye and pivot across the view so that the pivot's plane follows the pointer:
    /// `dx`, `dy` pixels dragged in a view `height` pixels high.
    pub fn pan(&mut self, dx: f32, dy: f32, height: u32) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        let half_height = match self.projection {
            Projection::Perspective { yfov, .. } => (self.target - self.eye).length() * (yfov * 0.5).tan(),
            Projection::Orthographic { ymag, .. } => ymag,
        };
        let per_pixel = 2.0 * half_height / height.max(1) as f32;
        let right = self.right();
        let up = right.cross(self.forward());
        let shift = (-dx * right + dy * up) * per_pixel;
        self.eye += shift;
        self.target += shift;
        self.moved = true;
    }

    /// Moves the eye towards the pivot (`steps > 0`, wheel up) or away, by [`DOLLY_PER_STEP`]
    /// per step; an orthographic camera zooms its extent instead.
    pub fn dolly(&mut self, steps: f32) {
        if steps == 0.0 {
            return;
        }
        let f = DOLLY_PER_STEP.powf(steps);
        match &mut self.projection {
            Projection::Orthographic { ymag, xmag } => {
                *ymag *= f;
                *xmag *= f;
            }
            Projection::Perspective { .. } => {
                let offset = self.eye - self.target;
                let d = (offset.length() * f).max(self.scene_size * 1e-5);
                self.eye = self.target + offset.normalize_or(Vec3::Z) * d;
            }
        }
        self.moved = true;
    }

    /// Flies eye and pivot for `seconds` along the view (`forward`), across it (`right`) and
    /// along world up (`up`), each in −1..1, at [`FLY_SCENE_PER_SECOND`] (×4 when `fast`).
    pub fn fly(&mut self, forward: f32, right: f32, up: f32, seconds: f32, fast: bool) {
        if forward == 0.0 && right == 0.0 && up == 0.0 {
            return;
        }
        let speed = self.scene_size * FLY_SCENE_PER_SECOND * if fast { 4.0 } else { 1.0 };
        let shift = (forward * self.forward() + right * self.right() + up * self.up) * speed * seconds;
        self.eye += shift;
        self.target += shift;
        self.moved = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig() -> CameraRig {
        let cam = Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 0.8);
        CameraRig::new(cam, (Vec3::splat(-1.0), Vec3::new(1.0, 3.0, 1.0)))
    }

    #[test]
    fn the_start_camera_is_kept_exactly_until_moved() {
        let cam = Camera::look_at(Vec3::new(0.3, 1.0, 5.0), Vec3::ZERO, Vec3::new(0.1, 1.0, 0.0), 0.8);
        let mut r = CameraRig::new(cam, (Vec3::splat(-1.0), Vec3::ONE));
        assert_eq!(r.camera(), cam);
        r.orbit(0.0, 0.0);
        assert!(!r.moved());
        r.orbit(10.0, 0.0);
        assert!(r.moved());
        assert_ne!(r.camera(), cam);
        r.reset();
        assert_eq!(r.camera(), cam);
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_pivot_and_turns_by_the_drag() {
        let mut r = rig();
        let d0 = (r.eye - r.target).length();
        // 360 pixels right = 90 degrees about +Y: the eye goes from +Z to −X of the pivot... or
        // +X; check the angle and the distance.
        r.orbit(360.0, 0.0);
        let off = r.eye - r.target;
        assert!((off.length() - d0).abs() < 1e-4 * d0, "{off}");
        assert!(off.z.abs() < 1e-4 * d0 && off.y.abs() < 1e-4 * d0, "a quarter turn about +Y: {off}");
        // Pitching far past the pole stops short of it.
        r.orbit(0.0, 10_000.0);
        let off = (r.eye - r.target).normalize();
        let from_up = off.dot(Vec3::Y).acos().to_degrees();
        assert!(
            (from_up - POLE_MARGIN_DEGREES).abs() < 0.01
                || (180.0 - from_up - POLE_MARGIN_DEGREES).abs() < 0.01,
            "{from_up}"
        );
        assert!(r.camera().world_from_camera.is_finite());
    }

    #[test]
    fn pan_moves_the_pivot_plane_with_the_pointer() {
        let mut r = rig();
        let (e, t) = (r.eye, r.target);
        // Dragging a whole view height moves the pivot plane by its full visible height.
        r.pan(0.0, 100.0, 100);
        let visible = 2.0 * (t - e).length() * (0.8f32 * 0.5).tan();
        assert!(((r.target - t).length() - visible).abs() < 1e-4, "{}", (r.target - t).length());
        assert!((r.eye - e - (r.target - t)).length() < 1e-5, "eye and pivot move together");
        assert!(r.target.y > t.y, "dragging down moves the camera up (the scene follows the pointer down)");
    }

    #[test]
    fn dolly_scales_the_distance_and_never_crosses_the_pivot() {
        let mut r = rig();
        let d0 = (r.eye - r.target).length();
        r.dolly(1.0);
        assert!(((r.eye - r.target).length() - d0 * DOLLY_PER_STEP).abs() < 1e-5);
        r.dolly(-1.0);
        assert!(((r.eye - r.target).length() - d0).abs() < 1e-4);
        r.dolly(10_000.0);
        let d = (r.eye - r.target).length();
        assert!(d > 0.0 && (r.eye - r.target).dot(Vec3::Z) > 0.0, "still in front of the pivot: {d}");
    }

    #[test]
    fn fly_moves_along_the_view_at_scene_speed() {
        let mut r = rig();
        let e = r.eye;
        r.fly(1.0, 0.0, 0.0, 1.0, false);
        let size = (Vec3::new(1.0, 3.0, 1.0) - Vec3::splat(-1.0)).length();
        assert!(((e - r.eye).length() - size * FLY_SCENE_PER_SECOND).abs() < 1e-4);
        assert!(r.eye.z < e.z, "forward is −Z here");
        r.look(100.0, 0.0);
        assert!(
            (r.eye - (e + Vec3::NEG_Z * size * FLY_SCENE_PER_SECOND)).length() < 1e-4,
            "look keeps the eye"
        );
    }

    #[test]
    fn orthographic_cameras_zoom_their_extent() {
        let mut cam = Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 0.8);
        cam.projection = Projection::Orthographic { xmag: 2.0, ymag: 1.0 };
        let mut r = CameraRig::new(cam, (Vec3::splat(-1.0), Vec3::ONE));
        r.dolly(1.0);
        assert_eq!(r.camera().projection, Projection::Orthographic { xmag: 1.8, ymag: 0.9 });
    }
}
