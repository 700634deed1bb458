//! The scene to render and its node hierarchy, flattened depth-first into world space:
//! cameras, punctual lights and mesh primitives; the sky from the scene's extras.

use super::context::Ctx;
use super::primitive::Meshes;
use crate::camera::{Camera, Projection};
use crate::error::SceneError;
use crate::{Light, Sun};
use glam::{Affine3A, Mat4, Vec3};

/// What the nodes of the scene hold, in world space.
pub(super) struct Flattened<'b> {
    /// The primitives' triangles.
    pub(super) meshes: Meshes<'b>,
    /// Cameras in traversal order.
    pub(super) cameras: Vec<Camera>,
    /// The first directional light.
    pub(super) sun: Option<Sun>,
    /// The other supported lights.
    pub(super) lights: Vec<Light>,
}

/// The file's default scene, else its first.
pub(super) fn scene_to_render<'d>(
    ctx: &Ctx<'_>,
    doc: &'d gltf::Document,
) -> Result<gltf::Scene<'d>, SceneError> {
    doc.default_scene().or_else(|| doc.scenes().next()).ok_or_else(|| SceneError::NothingToRender {
        file: ctx.file.to_string(),
        reason: "the file has no scene".into(),
    })
}

/// The sky's radiance from `extras.background_radiance_rgb` (black without it; a malformed
/// one is ignored with a warning).
pub(super) fn read_sky(ctx: &mut Ctx<'_>, scene: &gltf::Scene<'_>) -> Vec3 {
    let mut sky = Vec3::ZERO;
    if let Some(raw) = scene.extras()
        && let Ok(v) = gltf::json::deserialize::from_str::<gltf::json::Value>(raw.get())
        && let Some(bg) = v.get("background_radiance_rgb")
    {
        let arr: Option<Vec<f32>> =
            bg.as_array().map(|a| a.iter().filter_map(|x| x.as_f64().map(|x| x as f32)).collect());
        match arr {
            Some(a) if a.len() == 3 && a.iter().all(|x| x.is_finite() && *x >= 0.0) => {
                sky = Vec3::new(a[0], a[1], a[2]);
            }
            _ => ctx.warn(
                format!("scenes[{}].extras.background_radiance_rgb", scene.index()),
                "not three non-negative numbers: sky left black",
            ),
        }
    }
    sky
}

/// The environment map of `extras.environment = {"uri": "NAME.exr", "intensity": k}` (the
/// references' convention; the URI relative to the scene file), if the scene names one. A
/// malformed entry is ignored with a warning; a map that cannot be read is an error naming both
/// files.
pub(super) fn read_environment(
    ctx: &mut Ctx<'_>,
    scene: &gltf::Scene<'_>,
) -> Result<Option<crate::Environment>, SceneError> {
    let Some(raw) = scene.extras() else { return Ok(None) };
    let Ok(v) = gltf::json::deserialize::from_str::<gltf::json::Value>(raw.get()) else { return Ok(None) };
    let Some(env) = v.get("environment") else { return Ok(None) };
    let path = format!("scenes[{}].extras.environment", scene.index());
    let Some(uri) = env.get("uri").and_then(|u| u.as_str()) else {
        ctx.warn(&path, "no \"uri\" string: environment ignored");
        return Ok(None);
    };
    let intensity = match env.get("intensity") {
        None => 1.0,
        Some(k) => match k.as_f64() {
            Some(k) if k.is_finite() && k >= 0.0 => k as f32,
            _ => {
                ctx.warn(format!("{path}.intensity"), "not a non-negative number: 1 used");
                1.0
            }
        },
    };
    if uri.contains("://") || uri.starts_with("data:") {
        ctx.warn(
            format!("{path}.uri"),
            format!("'{uri}': only relative file URIs are supported: environment ignored"),
        );
        return Ok(None);
    }
    let Some(base) = ctx.base else {
        ctx.warn(
            format!("{path}.uri"),
            "a scene loaded from memory cannot resolve a file: environment ignored",
        );
        return Ok(None);
    };
    let (map, warning) =
        crate::EnvironmentMap::load(base.join(super::resources::percent_decode(uri))).map_err(|source| {
            SceneError::Environment { file: ctx.file.to_string(), path: format!("{path}.uri"), source }
        })?;
    if let Some(w) = warning {
        ctx.warn(format!("{path}.uri"), w);
    }
    Ok(Some(crate::Environment { intensity, ..crate::Environment::new(std::sync::Arc::new(map)) }))
}

/// Walks `scene`'s nodes depth-first (children in file order), each once, adding what they
/// hold to `meshes` and the cameras and lights; a subtree with a non-finite transform is
/// skipped with a warning.
pub(super) fn flatten<'b>(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    scene: &gltf::Scene<'_>,
    meshes: Meshes<'b>,
) -> Result<Flattened<'b>, SceneError> {
    let mut out = Flattened { meshes, cameras: Vec::new(), sun: None, lights: Vec::new() };
    let mut visited = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let npath = format!("nodes[{}]", node.index());
        if std::mem::replace(&mut visited[node.index()], true) {
            ctx.warn(npath, "node reached twice (cycle or shared child): skipped");
            continue;
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            ctx.warn(npath, "non-finite transform: subtree skipped");
            continue;
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
        out.add_node(ctx, &node, &npath, world)?;
    }
    Ok(out)
}

impl Flattened<'_> {
    /// Adds node `node` (JSON path `npath`)'s camera, light and mesh, placed by `world`.
    fn add_node(
        &mut self,
        ctx: &mut Ctx<'_>,
        node: &gltf::Node<'_>,
        npath: &str,
        world: Mat4,
    ) -> Result<(), SceneError> {
        if node.skin().is_some() || node.weights().is_some() {
            ctx.warn(npath, "skinning and morph targets are not supported: rest pose used");
        }
        if let Some(cam) = node.camera() {
            self.cameras.push(make_camera(ctx, &cam, world));
        }
        if let Some(light) = node.light() {
            self.add_light(ctx, &light, world);
        }
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let ppath = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                self.meshes.add_primitive(ctx, &prim, &ppath, npath, world)?;
            }
        }
        Ok(())
    }

    /// The first directional light becomes the sun; an unsupported light is ignored with a
    /// warning.
    fn add_light(&mut self, ctx: &mut Ctx<'_>, light: &gltf::khr_lights_punctual::Light<'_>, world: Mat4) {
        let lpath = format!("KHR_lights_punctual.lights[{}]", light.index());
        match crate::light::punctual(light, world) {
            Ok(Light::Sun(_)) if self.sun.is_some() => {
                ctx.warn(lpath, "only the first directional light is used as the sun");
            }
            Ok(Light::Sun(mut s)) => {
                s.angular_radius = angular_radius(ctx, light, &lpath);
                self.sun = Some(s);
            }
            Ok(other) => self.lights.push(other),
            Err((path, why)) => ctx.warn(if path.is_empty() { lpath } else { path.to_string() }, why),
        }
    }
}

/// Half the angular diameter (radians) of a directional light's disc, from the light's
/// `extras.angular_diameter_deg` (the references' convention): 0 (a delta sun) without it; a
/// value outside `[0°, 180°]` or not a number is ignored with a warning.
fn angular_radius(ctx: &mut Ctx<'_>, light: &gltf::khr_lights_punctual::Light<'_>, lpath: &str) -> f32 {
    let Some(raw) = light.extras() else { return 0.0 };
    let Ok(v) = gltf::json::deserialize::from_str::<gltf::json::Value>(raw.get()) else { return 0.0 };
    let Some(d) = v.get("angular_diameter_deg") else { return 0.0 };
    match d.as_f64() {
        Some(deg) if (0.0..=180.0).contains(&deg) => (deg.to_radians() / 2.0) as f32,
        _ => {
            ctx.warn(
                format!("{lpath}.extras.angular_diameter_deg"),
                "not a number of degrees in [0, 180]: the sun is a delta light",
            );
            0.0
        }
    }
}

fn make_camera(ctx: &mut Ctx<'_>, cam: &gltf::Camera<'_>, world: Mat4) -> Camera {
    // Remove scale: keep rotation (orthonormalised columns) and translation.
    let (_, rot, t) = world.to_scale_rotation_translation();
    let world_from_camera = Affine3A::from_rotation_translation(rot.normalize(), t);
    let projection = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let yfov = p.yfov();
            if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                ctx.warn(
                    format!("cameras[{}].perspective.yfov", cam.index()),
                    "yfov outside (0, π): 45° used",
                );
            }
            Projection::Perspective {
                yfov: if yfov > 0.0 && yfov < std::f32::consts::PI {
                    yfov
                } else {
                    crate::camera::DEFAULT_YFOV
                },
                aspect_ratio: p.aspect_ratio(),
            }
        }
        gltf::camera::Projection::Orthographic(o) => {
            Projection::Orthographic { xmag: o.xmag(), ymag: o.ymag() }
        }
    };
    Camera { world_from_camera, projection }
}
