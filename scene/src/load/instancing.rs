//! `EXT_mesh_gpu_instancing`: a node that places its mesh once per instance, each instance's
//! transform the node's world transform × a TRS read from the extension's `TRANSLATION`,
//! `ROTATION` and `SCALE` accessors (each optional, identity without it; all of one count).
//! The extension moves only the mesh: the node's camera, light and children are placed once.
//!
//! Which meshes are stored once ([`shared_meshes`]): every mesh placed more than once (by
//! nodes or by this extension's instances) unless a placement is skinned, the mesh has morph
//! targets (its shape depends on the node's weights) or it may emit light (each emitting
//! instance is a light of its own, kept in world space for the light list); the others are
//! flattened into world-space triangles.

use super::context::Ctx;
use crate::accessor::read_floats;
use crate::error::SceneError;
use glam::{Mat4, Quat, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::Value;

/// The extension's name, as files list it.
pub(super) const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// The attributes that place an instance, with the accessor type each must have.
const ATTRIBUTES: [(&str, Dimensions); 3] =
    [("TRANSLATION", Dimensions::Vec3), ("ROTATION", Dimensions::Vec4), ("SCALE", Dimensions::Vec3)];

/// How many copies of its mesh `node` places, from the accessors' counts alone (nothing is
/// read): 1 without the extension, else the largest count among its attributes (an upper
/// bound: counts that differ are refused when the instances are read). A malformed extension
/// counts 1 here and is refused by [`instances`].
pub(super) fn declared_count(doc: &gltf::Document, node: &gltf::Node<'_>) -> u64 {
    let Some(attributes) = node.extension_value(EXTENSION).and_then(|e| e.get("attributes")) else {
        return 1;
    };
    let accessors = &doc.as_json().accessors;
    ATTRIBUTES
        .iter()
        .filter_map(|(name, _)| attributes.get(name)?.as_u64())
        .filter_map(|i| accessors.get(usize::try_from(i).ok()?))
        .map(|a| a.count.0)
        .max()
        .unwrap_or(1)
}

/// The transforms that place `node`'s mesh: `[world]` without the extension, else
/// `world × T·R·S` for each instance. A missing or malformed `attributes`, an accessor of the
/// wrong type, counts that differ, a non-finite value or a zero rotation is an error naming the
/// file and the attribute's glTF path.
pub(super) fn instances(
    ctx: &Ctx<'_>,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    node: &gltf::Node<'_>,
    npath: &str,
    world: Mat4,
) -> Result<Vec<Mat4>, SceneError> {
    let Some(ext) = node.extension_value(EXTENSION) else { return Ok(vec![world]) };
    let epath = format!("{npath}.extensions.{EXTENSION}");
    let Some(attributes) = ext.get("attributes").and_then(Value::as_object) else {
        return Err(ctx.invalid((format!("{epath}.attributes"), "missing or not an object".into())));
    };
    let mut columns: [Option<Column>; 3] = [None, None, None];
    for ((name, dims), column) in ATTRIBUTES.iter().zip(&mut columns) {
        let Some(index) = attributes.get(*name) else { continue };
        let path = format!("{epath}.attributes.{name}");
        let acc = index.as_u64().and_then(|i| doc.accessors().nth(usize::try_from(i).ok()?));
        let Some(acc) = acc else {
            let n = doc.accessors().len();
            return Err(ctx.invalid((path, format!("not the index of one of the {n} accessors"))));
        };
        check_type(&acc, name, *dims).map_err(|m| ctx.invalid((path.clone(), m)))?;
        let (values, width) = read_floats(&acc, buffers, &[*dims])
            .map_err(|(apath, m)| ctx.invalid((path.clone(), format!("{apath}: {m}"))))?;
        if let Some(i) = values.iter().position(|x| !x.is_finite()) {
            return Err(ctx.invalid((
                path,
                format!(
                    "instance {} has a non-finite value ({}): values must be finite",
                    i / width,
                    values[i]
                ),
            )));
        }
        *column = Some(Column { values, width, path });
    }
    let mut present = columns.iter().flatten();
    let Some(first) = present.next() else {
        return Err(ctx.invalid((
            format!("{epath}.attributes"),
            "none of TRANSLATION, ROTATION, SCALE: no instance to place".into(),
        )));
    };
    let count = first.count();
    if let Some(other) = present.find(|c| c.count() != count) {
        return Err(ctx.invalid((
            other.path.clone(),
            format!(
                "{} instances, but {} has {count}: every attribute must have the same count",
                other.count(),
                first.path
            ),
        )));
    }
    let [t, r, s] = &columns;
    (0..count)
        .map(|i| {
            let translation = t.as_ref().map_or(Vec3::ZERO, |c| Vec3::from_slice(c.get(i)));
            let scale = s.as_ref().map_or(Vec3::ONE, |c| Vec3::from_slice(c.get(i)));
            let rotation = match r {
                None => Quat::IDENTITY,
                Some(c) => {
                    let q = c.get(i);
                    // In f64, where the norm of finite f32 components neither overflows nor
                    // underflows.
                    let norm = q.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>().sqrt();
                    if norm == 0.0 {
                        return Err(ctx.invalid((
                            c.path.clone(),
                            format!("instance {i} has a zero quaternion: not a rotation"),
                        )));
                    }
                    // Unit quaternions, as glTF stores them, within the rounding of their
                    // encoding (1/127 for normalised bytes): normalised so that none scales.
                    let unit = |k: usize| (f64::from(q[k]) / norm) as f32;
                    Quat::from_xyzw(unit(0), unit(1), unit(2), unit(3))
                }
            };
            let placed = world * Mat4::from_scale_rotation_translation(scale, rotation, translation);
            if !placed.is_finite() {
                return Err(ctx.invalid((
                    format!("{epath}.attributes"),
                    format!("instance {i}'s transform times the node's is beyond f32's range (3.4e38)"),
                )));
            }
            Ok(placed)
        })
        .collect()
}

/// For each mesh of `doc`, whether `scene` stores it once and places it by instances (see the
/// module's text): `emissive[m]` says material `m` may emit (the default material last).
pub(super) fn shared_meshes(doc: &gltf::Document, scene: &gltf::Scene<'_>, emissive: &[bool]) -> Vec<bool> {
    let meshes = doc.meshes().len();
    let mut placements = vec![0u64; meshes];
    let mut skinned = vec![false; meshes];
    let mut visited = vec![false; doc.nodes().len()];
    let mut stack: Vec<gltf::Node<'_>> = scene.nodes().collect();
    while let Some(node) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            continue;
        }
        stack.extend(node.children());
        let Some(mesh) = node.mesh() else { continue };
        placements[mesh.index()] += declared_count(doc, &node);
        skinned[mesh.index()] |= node.skin().is_some();
    }
    let default_material = emissive.len().saturating_sub(1);
    let emits = |i: usize| emissive.get(i).copied().unwrap_or(true);
    doc.meshes()
        .map(|mesh| {
            let m = mesh.index();
            placements[m] >= 2
                && !skinned[m]
                && mesh.primitives().all(|p| {
                    let own = p.material().index().unwrap_or(default_material);
                    // A variant may map the primitive to another material.
                    let mapped = p
                        .extension_value("KHR_materials_variants")
                        .and_then(|v| v.get("mappings"))
                        .and_then(Value::as_array)
                        .into_iter()
                        .flatten()
                        .filter_map(|mapping| mapping.get("material")?.as_u64());
                    p.morph_targets().len() == 0
                        && !emits(own)
                        && mapped.into_iter().all(|i| !emits(usize::try_from(i).unwrap_or(usize::MAX)))
                })
        })
        .collect()
}

/// One attribute's values, `width` floats an instance, and its glTF path.
struct Column {
    values: Vec<f32>,
    width: usize,
    path: String,
}

impl Column {
    fn count(&self) -> usize {
        self.values.len() / self.width
    }

    /// Instance `i`'s values.
    fn get(&self, i: usize) -> &[f32] {
        &self.values[self.width * i..self.width * (i + 1)]
    }
}

/// The accessor types the extension allows: `TRANSLATION` and `SCALE` VEC3 of floats (or, as
/// KHR_mesh_quantization allows, of bytes or shorts, normalised or not); `ROTATION` VEC4 of
/// floats or of normalised signed bytes or shorts.
fn check_type(acc: &gltf::Accessor<'_>, name: &str, dims: Dimensions) -> Result<(), String> {
    let (t, normalized) = (acc.data_type(), acc.normalized());
    let ok = acc.dimensions() == dims
        && match name {
            "ROTATION" => t == DataType::F32 || (normalized && matches!(t, DataType::I8 | DataType::I16)),
            _ => t != DataType::U32 && !(t == DataType::F32 && normalized),
        };
    if ok {
        return Ok(());
    }
    let allowed = if name == "ROTATION" {
        "VEC4 of floats or of normalised signed bytes or shorts"
    } else {
        "VEC3 of floats, bytes or shorts"
    };
    let norm = if normalized { "normalised " } else { "" };
    Err(format!(
        "accessors[{}] is {:?} of {norm}{t:?}: {name} must be {allowed}",
        acc.index(),
        acc.dimensions()
    ))
}
