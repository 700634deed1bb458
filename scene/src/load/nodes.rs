//! The scene to render and its node hierarchy, flattened depth-first into world space at the
//! animation's pose: cameras, punctual lights and mesh primitives (posed by their morph weights
//! and skins); the sky from the scene's extras.

use super::animation::Pose;
use super::context::Ctx;
use super::primitive::Meshes;
use super::primitive::pose::Posing;
use super::skin::JointMatrices;
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
    /// The nodes' transforms and morph weights.
    pose: &'b Pose,
    /// Every node's world transform at the pose (computed only when the file has skins).
    worlds: Vec<Option<Mat4>>,
    /// Each skin's joint matrices, computed when a node first uses it.
    skins: Vec<Option<JointMatrices>>,
    /// Per glTF mesh: stored once and placed by instances ([`super::instancing::shared_meshes`]).
    shared: Vec<bool>,
    /// Per glTF mesh: its index in `instancing.meshes` once stored.
    slots: Vec<Option<u32>>,
    /// The shared meshes (triangle ranges of `meshes.object`) and their placements.
    pub(super) instancing: crate::Instancing,
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
    let rel = super::resources::percent_decode(uri);
    if crate::file::is_absolute_uri_path(&rel) {
        return Err(ctx.invalid((format!("{path}.uri"), super::resources::absolute_uri_message(&rel))));
    }
    let (map, warning) = crate::EnvironmentMap::load(base.join(rel)).map_err(|source| {
        SceneError::Environment { file: ctx.file.to_string(), path: format!("{path}.uri"), source }
    })?;
    if let Some(w) = warning {
        ctx.warn(format!("{path}.uri"), w);
    }
    Ok(Some(crate::Environment { intensity, ..crate::Environment::new(std::sync::Arc::new(map)) }))
}

/// What `scene` will store, from the accessors' counts alone (nothing is read): the triangles
/// (each node once, as [`flatten`] visits them; each triangle primitive's triangles — a list's
/// index count, or vertex count, / 3; a strip's or fan's count − 2 — per node that places its
/// mesh, times its instances (`EXT_mesh_gpu_instancing`), or once for a mesh `shared` marks)
/// and the instances of shared meshes. Upper bounds: `flatten` may still skip subtrees and drop
/// triangles.
pub(super) struct Declared {
    /// Triangles stored.
    pub(super) triangles: u64,
    /// Placements of shared meshes.
    pub(super) instances: u64,
}

/// [`Declared`] for `scene`, `shared[m]` saying whether mesh `m` is stored once.
pub(super) fn declared(doc: &gltf::Document, scene: &gltf::Scene<'_>, shared: &[bool]) -> Declared {
    let json = doc.as_json();
    let count =
        |i: gltf::json::Index<gltf::json::Accessor>| json.accessors.get(i.value()).map_or(0, |a| a.count.0);
    let mut visited = vec![false; json.nodes.len()];
    let mut stored = vec![false; json.meshes.len()];
    let mut stack: Vec<gltf::Node<'_>> = scene.nodes().collect();
    let mut out = Declared { triangles: 0, instances: 0 };
    while let Some(node) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            continue;
        }
        stack.extend(node.children());
        let Some(mesh) = node.mesh().and_then(|m| json.meshes.get(m.index())) else { continue };
        let m = node.mesh().map_or(0, |m| m.index());
        let mut copies = super::instancing::declared_count(doc, &node);
        if shared.get(m).copied().unwrap_or(false) && node.skin().is_none() {
            out.instances = out.instances.saturating_add(copies);
            if std::mem::replace(&mut stored[m], true) {
                continue;
            }
            copies = 1;
        }
        for p in &mesh.primitives {
            use gltf::mesh::Mode;
            let mode = match p.mode {
                gltf::json::validation::Checked::Valid(m) => Some(m),
                gltf::json::validation::Checked::Invalid => None,
            };
            let vertices = match (
                &p.indices,
                p.attributes.get(&gltf::json::validation::Checked::Valid(gltf::Semantic::Positions)),
            ) {
                (Some(i), _) => count(*i),
                (None, Some(pos)) => count(*pos),
                (None, None) => 0,
            };
            let triangles = match mode {
                Some(Mode::Triangles) => vertices / 3,
                Some(Mode::TriangleStrip | Mode::TriangleFan) => vertices.saturating_sub(2),
                _ => 0,
            };
            out.triangles = out.triangles.saturating_add(triangles.saturating_mul(copies));
        }
    }
    out
}

/// Walks `scene`'s nodes depth-first (children in file order), each once, at `pose`, adding
/// what they hold to `meshes` and the cameras and lights; a subtree with a non-finite transform
/// is skipped with a warning.
pub(super) fn flatten<'b>(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    scene: &gltf::Scene<'_>,
    meshes: Meshes<'b>,
    pose: &'b Pose,
    shared: Vec<bool>,
) -> Result<Flattened<'b>, SceneError> {
    let worlds = match doc.skins().len() {
        0 => Vec::new(),
        _ => super::skin::world_transforms(ctx, doc, pose),
    };
    let skins = vec![None; doc.skins().len()];
    let slots = vec![None; shared.len()];
    let mut out = Flattened {
        meshes,
        cameras: Vec::new(),
        sun: None,
        lights: Vec::new(),
        pose,
        worlds,
        skins,
        shared,
        slots,
        instancing: crate::Instancing::default(),
    };
    let mut visited = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let npath = format!("nodes[{}]", node.index());
        if std::mem::replace(&mut visited[node.index()], true) {
            ctx.warn(npath, "node reached twice (cycle or shared child): skipped");
            continue;
        }
        let Some(local) = local_transform(ctx, pose.transform(&node), &npath) else { continue };
        let world = parent * local;
        if !world.is_finite() {
            ctx.warn(npath, "non-finite transform: subtree skipped");
            continue;
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
        out.add_node(ctx, doc, &node, &npath, world)?;
    }
    Ok(out)
}

impl Flattened<'_> {
    /// Adds node `node` (JSON path `npath`)'s camera, light and mesh, placed by `world`.
    fn add_node(
        &mut self,
        ctx: &mut Ctx<'_>,
        doc: &gltf::Document,
        node: &gltf::Node<'_>,
        npath: &str,
        world: Mat4,
    ) -> Result<(), SceneError> {
        if let Some(cam) = node.camera()
            && let Some(camera) = make_camera(ctx, doc, &cam, npath, world)?
        {
            self.cameras.push(camera);
        }
        if let Some(light) = node.light() {
            self.add_light(ctx, &light, world);
        }
        if let Some(mesh) = node.mesh() {
            let worlds = super::instancing::instances(ctx, doc, self.meshes.buffers(), node, npath, world)?;
            let skin = match node.skin() {
                Some(skin) => {
                    if node.extension_value(super::instancing::EXTENSION).is_some() {
                        ctx.warn(
                            format!("{npath}.extensions.{}", super::instancing::EXTENSION),
                            "a skinned mesh is placed by its joints, once: instances ignored",
                        );
                    }
                    Some(self.joint_matrices(ctx, doc, &skin)?)
                }
                None => None,
            };
            let pose = self.pose;
            let posing = Posing {
                mesh: mesh.index(),
                weights: pose.weights(node),
                skin: skin.as_ref(),
                node_world: world,
            };
            if self.shared.get(mesh.index()).copied().unwrap_or(false) && skin.is_none() {
                let slot = self.shared_mesh(ctx, &mesh, npath, &posing)?;
                // A transform that collapses the mesh (a zero scale) places nothing.
                self.instancing
                    .instances
                    .extend(worlds.iter().filter_map(|&w| crate::Instance::new(slot, w)));
                return Ok(());
            }
            for prim in mesh.primitives() {
                let ppath = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                self.meshes.add_primitive(ctx, &prim, (&ppath, npath), &worlds, &posing)?;
            }
        } else if node.extension_value(super::instancing::EXTENSION).is_some() {
            ctx.warn(
                format!("{npath}.extensions.{}", super::instancing::EXTENSION),
                "the node has no mesh to instance: ignored",
            );
        }
        Ok(())
    }

    /// The index in `instancing.meshes` of shared `mesh`, its primitives read into the object
    /// store (in object space) the first time a node places it.
    fn shared_mesh(
        &mut self,
        ctx: &mut Ctx<'_>,
        mesh: &gltf::Mesh<'_>,
        npath: &str,
        posing: &Posing<'_>,
    ) -> Result<u32, SceneError> {
        if let Some(slot) = self.slots[mesh.index()] {
            return Ok(slot);
        }
        std::mem::swap(&mut self.meshes.geo, &mut self.meshes.object);
        let start = self.meshes.geo.triangle_count() as u32;
        let mut added = Ok(());
        for prim in mesh.primitives() {
            let ppath = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            added = self.meshes.add_primitive(ctx, &prim, (&ppath, npath), &[Mat4::IDENTITY], posing);
            if added.is_err() {
                break;
            }
        }
        let end = self.meshes.geo.triangle_count() as u32;
        std::mem::swap(&mut self.meshes.geo, &mut self.meshes.object);
        added?;
        let slot = self.instancing.meshes.len() as u32;
        self.instancing.meshes.push(start..end);
        self.slots[mesh.index()] = Some(slot);
        Ok(slot)
    }

    /// `skin`'s joint matrices at the pose (computed once per skin).
    fn joint_matrices(
        &mut self,
        ctx: &Ctx<'_>,
        doc: &gltf::Document,
        skin: &gltf::Skin<'_>,
    ) -> Result<JointMatrices, SceneError> {
        if let Some(Some(m)) = self.skins.get(skin.index()) {
            return Ok(m.clone());
        }
        let m = super::skin::joint_matrices(ctx, doc, self.meshes.buffers(), skin, &self.worlds)?;
        if let Some(slot) = self.skins.get_mut(skin.index()) {
            *slot = Some(m.clone());
        }
        Ok(m)
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

/// A node's local transform. A TRS rotation must be a unit quaternion (glTF 2.0 §5.25): one
/// whose norm is off by more than the rounding of a written file (10⁻³) is normalised with a
/// warning (unnormalised, it would scale and shear the subtree, and a camera's view with it);
/// one that cannot be normalised (zero or not finite) skips the subtree with a warning.
pub(super) fn local_transform(ctx: &mut Ctx<'_>, t: gltf::scene::Transform, npath: &str) -> Option<Mat4> {
    let t = match t {
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let norm = rotation.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                ctx.warn(
                    format!("{npath}.rotation"),
                    "not a rotation (a zero or non-finite quaternion): subtree skipped",
                );
                return None;
            }
            let rotation = if (norm - 1.0).abs() > 1e-3 {
                ctx.warn(
                    format!("{npath}.rotation"),
                    format!("quaternion of norm {norm:.6e}, not a unit quaternion: normalised"),
                );
                rotation.map(|c| (f64::from(c) / norm) as f32)
            } else {
                rotation
            };
            gltf::scene::Transform::Decomposed { translation, rotation, scale }
        }
        matrix => matrix,
    };
    Some(Mat4::from_cols_array_2d(&t.matrix()))
}

/// The camera `cam` of node `npath`, placed by `world`, or none (with a warning) when `world`
/// gives it no orientation. The projection is read from the JSON: a `type` whose object is
/// missing is an error (gltf's `Camera::projection` would panic), as is an orthographic view of
/// zero or non-finite size (glTF 2.0 §5.12: `xmag`, `ymag` must not be zero).
fn make_camera(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    cam: &gltf::Camera<'_>,
    npath: &str,
    world: Mat4,
) -> Result<Option<Camera>, SceneError> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    let cpath = format!("cameras[{}]", cam.index());
    let Some(json) = doc.as_json().cameras.get(cam.index()) else {
        return Err(ctx.invalid((cpath, "camera does not exist".into())));
    };
    let projection = match (json.type_, &json.perspective, &json.orthographic) {
        (Checked::Valid(Type::Perspective), Some(p), _) => {
            let yfov = p.yfov;
            let valid = yfov > 0.0 && yfov < std::f32::consts::PI;
            if !valid {
                ctx.warn(format!("{cpath}.perspective.yfov"), "yfov outside (0, π): 45° used");
            }
            Projection::Perspective {
                yfov: if valid { yfov } else { crate::camera::DEFAULT_YFOV },
                aspect_ratio: p.aspect_ratio,
            }
        }
        (Checked::Valid(Type::Orthographic), _, Some(o)) => {
            let xmag = magnification(ctx, &cpath, "xmag", o.xmag)?;
            let ymag = magnification(ctx, &cpath, "ymag", o.ymag)?;
            Projection::Orthographic { xmag, ymag }
        }
        (Checked::Valid(t), _, _) => {
            let name = if t == Type::Perspective { "perspective" } else { "orthographic" };
            return Err(
                ctx.invalid((cpath, format!("type is \"{name}\" but the camera has no \"{name}\" object")))
            );
        }
        (Checked::Invalid, _, _) => {
            return Err(
                ctx.invalid((format!("{cpath}.type"), "not \"perspective\" or \"orthographic\"".into()))
            );
        }
    };
    if json.perspective.is_some() && json.orthographic.is_some() {
        ctx.warn(
            &cpath,
            "both \"perspective\" and \"orthographic\" are defined (glTF allows one): the one its type names is used",
        );
    }
    let Some(world_from_camera) = camera_frame(world) else {
        ctx.warn(
            npath,
            format!(
                "{cpath}: the node's transform collapses the camera's view or up axis (a scale of 0): \
                 camera ignored"
            ),
        );
        return Ok(None);
    };
    let position = Vec3::from(world_from_camera.translation);
    if position.abs().max_element() > crate::MAX_COORDINATE {
        ctx.warn(
            npath,
            format!(
                "{cpath}: the camera is at ({:e}, {:e}, {:e}), beyond the ±{:.1e} within which f32 ray tracing \
                 holds: the view may be black",
                position.x,
                position.y,
                position.z,
                crate::MAX_COORDINATE
            ),
        );
    }
    Ok(Some(Camera { world_from_camera, projection }))
}

/// An orthographic camera's `xmag` or `ymag` (`field`): zero or not finite is an error; a
/// negative one (which glTF 2.0 says should not be) is used by its magnitude with a warning, as
/// furnace does not mirror views; one beyond [`crate::MAX_COORDINATE`] is kept with a warning,
/// as rays from so wide a film start outside the range f32 ray tracing handles.
fn magnification(ctx: &mut Ctx<'_>, cpath: &str, field: &str, value: f32) -> Result<f32, SceneError> {
    let path = format!("{cpath}.orthographic.{field}");
    if !(value.is_finite() && value != 0.0) {
        return Err(
            ctx.invalid((path, format!("{field} is {value}: it must be a finite number other than 0")))
        );
    }
    if value < 0.0 {
        ctx.warn(
            &path,
            format!("{field} is negative ({value}): its magnitude is used (views are not mirrored)"),
        );
    }
    let value = value.abs();
    if value > crate::MAX_COORDINATE {
        ctx.warn(
            &path,
            format!(
                "{field} {value:e} is beyond the ±{:.1e} within which f32 ray tracing holds: the view may be black",
                crate::MAX_COORDINATE
            ),
        );
    }
    Ok(value)
}

/// The camera's rotation and translation from its node's world transform, any scale, shear or
/// mirror removed. For column lengths in 1e-12 … 1e12, glam's f32 decomposition; otherwise the
/// view axis (the transform's −Z column) and the up axis (its +Y column made
/// orthogonal to the view) are kept, and right completes a right-handed frame. Computed in f64
/// so that scales from 1e-38 to 1e38 lose nothing (in f32 their squared lengths underflow or
/// overflow). `None` when the view axis is zero or the up axis parallel to it (within 10⁻⁶
/// relative, well above f64's rounding of the f32 inputs).
fn camera_frame(world: Mat4) -> Option<Affine3A> {
    // Columns of ordinary lengths keep f32's decomposition, bit for bit what earlier versions
    // computed (saved renders keep their scene hash and resume).
    let ordinary = [world.x_axis, world.y_axis, world.z_axis]
        .iter()
        .all(|c| (1e-12..=1e12).contains(&c.truncate().length()));
    if ordinary {
        let (_, rotation, t) = world.to_scale_rotation_translation();
        let rotation = rotation.normalize();
        if rotation.is_finite() && t.is_finite() {
            return Some(Affine3A::from_rotation_translation(rotation, t));
        }
    }
    let col = |c: glam::Vec4| glam::DVec3::new(f64::from(c.x), f64::from(c.y), f64::from(c.z));
    let (y, z) = (col(world.y_axis), col(world.z_axis));
    let back = z.normalize_or_zero();
    let up = y - y.dot(back) * back;
    if back == glam::DVec3::ZERO || !(up.length() > 1e-6 * y.length()) {
        return None;
    }
    let up = up.normalize();
    let right = up.cross(back);
    let rot = glam::Mat3::from_cols(right.as_vec3(), up.as_vec3(), back.as_vec3());
    let rotation = glam::Quat::from_mat3(&rot).normalize();
    Some(Affine3A::from_rotation_translation(rotation, world.w_axis.truncate()))
}
