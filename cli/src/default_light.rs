//! The default light: whether `furnace render` (and `view`, `bench`, `chart`) adds the built-in
//! studio environment to a scene given no `--env` and no environment of its own.
//!
//! The rule, in order:
//! 1. a scene without a light of its own ([`Scene::has_own_light`]: emissive textures alone are
//!    glow, not light) gets the studio;
//! 2. a scene with a sky keeps it (the sky is its environment);
//! 3. a scene with lights of its own gets the studio when its view is open: when, of the rays
//!    leaving the surfaces its default camera sees, at least [`OPEN_THRESHOLD`] leave the scene
//!    ([`openness`]). An object shown in empty space (a product with a key light, a lamp with
//!    its bulbs) has lights made to be added to a viewer's environment: alone they leave it a
//!    dark shape on black. A room or box around its lights (the Cornell boxes) is lit by them
//!    and their inter-reflections, and keeps them alone.
//!
//! Why openness and not the lights' strength: the classic Cornell box's panel lights the box
//! 5–10 times less than the studio would, while GlamVelvetSofa's key light lights the sofa a
//! third as well as the studio; a rule on the lights' level ranks them the wrong way round
//! (docs/environment.md, "The default light", tabulates both).

use furnace_accel::{InstanceHit, SceneAccel, offset_ray_origin_scaled, offset_scale_of_bounds};
use furnace_cpu::CpuRenderer;
use furnace_scene::{Projection, Scene};
use glam::{Vec2, Vec3};

/// The openness at and above which a scene with lights of its own gets the studio. The Cornell
/// boxes measure 0.25–0.34 and the sample assets with lights 0.74–0.96 (docs/environment.md):
/// 0.5 lies about 1.5× from both.
pub const OPEN_THRESHOLD: f32 = 0.5;

/// Probe image width in pixels (its height follows the camera's aspect ratio, 4:3 without one):
/// 3 072 surface points at 4:3, enough for the openness to two decimals.
pub const PROBE_WIDTH: u32 = 64;
/// Rays cast over the hemisphere of each surface point the probe sees.
pub const PROBE_RAYS: u32 = 32;

/// Why the default light is or is not added.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Why {
    /// No light of its own: the studio.
    NoLight,
    /// A sky of its own: no studio.
    Sky,
    /// Lights of its own and an open view (the openness measured): the studio.
    Open(f32),
    /// Lights of its own and an enclosed view (the openness measured): no studio.
    Enclosed(f32),
    /// As the render being resumed recorded (`furnace.default_light`).
    Recorded,
    /// A render being resumed that records no decision (written before the rule): the rule of
    /// then, the studio only for a scene without a light of its own.
    BeforeTheRule,
}

/// The default light's decision: whether the studio is added, and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// Whether the built-in studio is added.
    pub studio: bool,
    /// Why.
    pub why: Why,
}

/// The rule (see the module's documentation) for `scene`, which has no environment of its own,
/// tracing the probe's rays through `accel` when it holds a structure, else
/// building the one the CPU renderer would ([`CpuRenderer::accel_for`]) into it: the renderer
/// opened after takes it instead of building its own, so a scene's BVH is built once.
pub fn decide_with(scene: &Scene, accel: &mut Option<SceneAccel>) -> Decision {
    if !scene.has_own_light() {
        return Decision { studio: true, why: Why::NoLight };
    }
    if scene.sky() != Vec3::ZERO {
        return Decision { studio: false, why: Why::Sky };
    }
    let open = openness(scene, accel.get_or_insert_with(|| CpuRenderer::accel_for(scene)));
    if open >= OPEN_THRESHOLD {
        Decision { studio: true, why: Why::Open(open) }
    } else {
        Decision { studio: false, why: Why::Enclosed(open) }
    }
}

impl Decision {
    /// The EXR record of the decision (`studio` or `none`).
    pub fn record(&self) -> &'static str {
        if self.studio { "studio" } else { "none" }
    }

    /// The decision a resumed render's record gives: `Some(record)` the record
    /// (`furnace.default_light`), `None` a file written before the rule.
    pub fn resumed(scene: &Scene, record: Option<&str>) -> Result<Self, String> {
        match record {
            Some("studio") => Ok(Self { studio: true, why: Why::Recorded }),
            Some("none") => Ok(Self { studio: false, why: Why::Recorded }),
            Some(other) => Err(other.to_string()),
            None => Ok(Self { studio: !scene.has_own_light(), why: Why::BeforeTheRule }),
        }
    }

    /// Why, in words: `its lights face open space (openness 0.88 ≥ 0.5)`.
    pub fn reason(&self) -> String {
        match self.why {
            Why::NoLight => "it has no light of its own".into(),
            Why::Sky => "its sky lights it".into(),
            Why::Open(o) => format!(
                "its lights face open space ({o:.2} of the rays from what its camera sees leave the scene, \
                 ≥ {OPEN_THRESHOLD})"
            ),
            Why::Enclosed(o) => format!(
                "a room around its lights ({o:.2} of the rays from what its camera sees leave the scene, \
                 < {OPEN_THRESHOLD})"
            ),
            Why::Recorded => "as the render resumed recorded".into(),
            Why::BeforeTheRule => "as the render resumed was made (before the open-view rule)".into(),
        }
    }
}

/// Of the cosine-distributed rays leaving the surfaces that the scene's default camera sees,
/// the fraction that hit no triangle: 1 for a convex object in empty space, 0 inside a closed
/// room, 1 when the camera sees nothing. A fixed pattern ([`PROBE_WIDTH`] pixel centres,
/// [`PROBE_RAYS`] Hammersley directions each), so the same scene always measures the same.
/// Alpha masks and transmission are not looked at: every triangle blocks. The rays are traced
/// through `accel`, the scene's structure ([`CpuRenderer::accel_for`]).
pub fn openness(scene: &Scene, accel: &SceneAccel) -> f32 {
    let g = &scene.geometry;
    let inst = &scene.instancing;
    let (lo, hi) = scene.bounds();
    let scale = offset_scale_of_bounds(lo, hi);
    let camera = scene.default_camera();
    let aspect = match camera.projection {
        Projection::Perspective { aspect_ratio, .. } => aspect_ratio.unwrap_or(4.0 / 3.0),
        Projection::Orthographic { xmag, ymag } => xmag / ymag,
    };
    let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 4.0 / 3.0 };
    let width = PROBE_WIDTH;
    let height = ((width as f32 / aspect).round() as u32).clamp(1, 4 * PROBE_WIDTH);
    let rays = camera.rays(width, height);
    let (mut points, mut escaped) = (0u64, 0u64);
    for y in 0..height {
        for x in 0..width {
            let ray = rays.generate(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let Some(InstanceHit { hit, instance }) =
                accel.closest_hit(ray.origin, ray.direction, f32::INFINITY)
            else {
                continue;
            };
            let Some(mut vertices) = g.triangle(hit.triangle as usize) else { continue };
            if let Some(i) = instance.and_then(|i| inst.instances.get(i as usize)) {
                vertices = vertices.map(|v| i.point(v));
            }
            let [a, b, c] = vertices;
            let mut n = (b - a).cross(c - a).normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            // The side the camera sees.
            if n.dot(ray.direction) > 0.0 {
                n = -n;
            }
            points += 1;
            let origin = offset_ray_origin_scaled(ray.origin + ray.direction * hit.t, n, scale);
            let (t1, t2) = n.any_orthonormal_pair();
            // Hammersley points turned per pixel by golden-ratio steps, so that neighbouring
            // pixels do not share directions; cosine-distributed about the normal.
            let turn = ((y * width + x) as f32 * 0.618_034).fract();
            for i in 0..PROBE_RAYS {
                let u1 = (i as f32 + 0.5) / PROBE_RAYS as f32;
                let u2 = (i.reverse_bits() as f32 / 4_294_967_296.0 + turn).fract();
                let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
                let d = t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt();
                if !accel.occluded(origin, d, f32::INFINITY) {
                    escaped += 1;
                }
            }
        }
    }
    if points == 0 { 1.0 } else { escaped as f32 / (points * u64::from(PROBE_RAYS)) as f32 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_scene::{Light, PointLight, builtin};

    /// A scene of `quads` (each 4 corners, two triangles, material 0) lit by one point light at
    /// the origin, with a camera at `eye` looking at the origin.
    fn lit(quads: &[[Vec3; 4]], eye: Vec3) -> Scene {
        let mut scene = builtin::cornell_box().unwrap();
        let g = &mut scene.geometry;
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for q in quads {
            let i = positions.len() as u32;
            positions.extend_from_slice(q);
            triangles.push([i, i + 1, i + 2]);
            triangles.push([i, i + 2, i + 3]);
        }
        let normal = furnace_scene::oct_encode(Vec3::Y);
        g.normals = vec![normal; positions.len()];
        g.positions = positions;
        g.triangle_materials = vec![0; triangles.len()];
        g.triangles = triangles;
        scene.lights = vec![Light::Point(PointLight {
            position: Vec3::ZERO,
            intensity: Vec3::splat(10.0),
            range: None,
            spot: None,
        })];
        scene.cameras = vec![furnace_scene::Camera::look_at(eye, Vec3::ZERO, Vec3::Y, 0.8)];
        scene
    }

    /// The six faces of the cube `[-1, 1]³`, less those named in `open` (±x, ±y, ±z as 0..6).
    fn cube(open: &[usize]) -> Vec<[Vec3; 4]> {
        let mut quads = Vec::new();
        for axis in 0..3 {
            for (s, sign) in [(0, 1.0f32), (1, -1.0)] {
                if open.contains(&(2 * axis + s)) {
                    continue;
                }
                let (u, v, w) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3], Vec3::AXES[axis]);
                let c = w * sign;
                quads.push([c - u - v, c + u - v, c + u + v, c - u + v]);
            }
        }
        quads
    }

    /// A box open on one side (+z) seen from inside through the opening, is a room: enclosed. A
    /// single floor quad seen from above is in empty space: open. The figures are exact
    /// enough to sit far from the threshold: from a box's walls only the opening's solid angle
    /// escapes, from a plane every ray does.
    #[test]
    fn a_box_around_the_light_is_enclosed_a_plane_in_space_is_open() {
        let room = lit(&cube(&[4]), Vec3::new(0.0, 0.0, 0.9));
        let d = decide_with(&room, &mut None);
        let Why::Enclosed(o) = d.why else { panic!("{d:?}") };
        assert!(!d.studio && o < 0.3, "{o}");
        let floor = [[
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
        ]];
        let plane = lit(&floor, Vec3::new(0.0, 2.0, 3.0));
        let d = decide_with(&plane, &mut None);
        assert_eq!(d, Decision { studio: true, why: Why::Open(1.0) }, "nothing above a plane blocks a ray");
    }

    /// Both sides of the threshold with one scene: a box with more and more of its faces
    /// removed, seen from outside through its open +z side. Openness rises with each face
    /// taken away and the decision flips once, between 1 and 4 faces open.
    #[test]
    fn opening_a_box_face_by_face_crosses_the_threshold_once() {
        let eye = Vec3::new(0.3, 0.4, 4.0);
        let mut last = 0.0;
        let mut flips = 0;
        let mut studio = false;
        for open in [&[4][..], &[4, 0], &[4, 0, 1], &[4, 0, 1, 2], &[4, 0, 1, 2, 5]] {
            let d = decide_with(&lit(&cube(open), eye), &mut None);
            let o = match d.why {
                Why::Open(o) | Why::Enclosed(o) => o,
                other => panic!("{other:?}"),
            };
            assert!(o > last, "{open:?}: openness {o} after {last}");
            if d.studio != studio {
                flips += 1;
                studio = d.studio;
            }
            last = o;
        }
        assert!(studio && flips == 1, "the last, a single face, is open; one flip");
    }

    #[test]
    fn no_light_gets_the_studio_and_a_sky_keeps_the_scene_as_it_is() {
        let mut scene = builtin::cornell_box().unwrap();
        assert_eq!(
            decide_with(&scene, &mut None),
            Decision { studio: false, why: Why::Sky },
            "the built-in box has a sky"
        );
        scene.lights.clear();
        for m in &mut scene.materials {
            m.emissive = Vec3::ZERO;
        }
        assert_eq!(decide_with(&scene, &mut None), Decision { studio: true, why: Why::NoLight });
    }

    #[test]
    fn a_resumed_render_follows_its_record_or_the_rule_of_its_time() {
        let scene = lit(&cube(&[4, 0, 1, 2, 5]), Vec3::new(0.0, 0.0, 4.0));
        let resumed = |r| Decision::resumed(&scene, r);
        assert_eq!(resumed(Some("none")), Ok(Decision { studio: false, why: Why::Recorded }));
        assert_eq!(resumed(Some("studio")), Ok(Decision { studio: true, why: Why::Recorded }));
        // Before the rule, a scene with a light of its own got none.
        assert_eq!(resumed(None), Ok(Decision { studio: false, why: Why::BeforeTheRule }));
        assert_eq!(resumed(Some("sky")), Err("sky".into()));
    }
}
