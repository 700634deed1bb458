//! Skins (glTF 2.0 §3.7.3): every node's world transform at the pose, and a skin's joint
//! matrices from them.
//!
//! glTF's joint matrix is `inverse(world(mesh node)) · world(joint) · inverseBind`, and the
//! skinned vertex is then placed by the mesh node's world transform, which cancels the first
//! factor: the mesh node's own transform (and its parents') does not place a skinned mesh, only
//! the joints do (§3.7.3.2, Joint Hierarchy: "the transform of the skinned mesh node MUST be
//! ignored"; the Khronos sample viewer computes the same product). So the matrices kept here are `world(joint) · inverseBind`, which
//! place vertices in world space directly, and a mesh node whose transform cannot be inverted
//! (a scale of 0) still renders its skinned mesh.

use super::animation::Pose;
use super::context::Ctx;
use crate::accessor::read_floats;
use crate::error::SceneError;
use glam::Mat4;
use gltf::accessor::Dimensions;

/// A skin's joint matrices at the pose: joint j's `world · inverseBindMatrix`.
#[derive(Debug, Clone)]
pub(super) struct JointMatrices {
    /// The skin's JSON path (`skins[0]`).
    pub(super) path: String,
    pub(super) matrices: Vec<Mat4>,
}

/// Every node's world transform at `pose`, from the file's hierarchy (each node under its first
/// parent), whether or not the rendered scene holds it: a skin's joints need not. `None` for a
/// node in a cycle, or whose transform or a parent's is not finite or not a rotation (the
/// loader warns about those where it places them).
pub(super) fn world_transforms(ctx: &mut Ctx<'_>, doc: &gltf::Document, pose: &Pose) -> Vec<Option<Mat4>> {
    let nodes: Vec<gltf::Node<'_>> = doc.nodes().collect();
    let mut has_parent = vec![false; nodes.len()];
    for node in &nodes {
        for child in node.children() {
            if let Some(p) = has_parent.get_mut(child.index()) {
                *p = true;
            }
        }
    }
    let mut out = vec![None; nodes.len()];
    let mut visited = vec![false; nodes.len()];
    let mut stack: Vec<(usize, Mat4)> =
        (0..nodes.len()).rev().filter(|&i| !has_parent[i]).map(|i| (i, Mat4::IDENTITY)).collect();
    while let Some((i, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[i], true) {
            continue;
        }
        let node = &nodes[i];
        let Some(local) = super::nodes::local_transform(ctx, pose.transform(node), &format!("nodes[{i}]"))
        else {
            continue;
        };
        let world = parent * local;
        if !world.is_finite() {
            continue;
        }
        out[i] = Some(world);
        stack.extend(node.children().map(|c| (c.index(), world)).filter(|&(c, _)| c < nodes.len()));
    }
    out
}

/// The joint matrices of `skin` from the nodes' `worlds`: its `inverseBindMatrices` (MAT4
/// floats, at least one per joint; identity without the accessor) must be finite, and every
/// joint must have a world transform; else an error naming the skin's path.
pub(super) fn joint_matrices(
    ctx: &Ctx<'_>,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    skin: &gltf::Skin<'_>,
    worlds: &[Option<Mat4>],
) -> Result<JointMatrices, SceneError> {
    let path = format!("skins[{}]", skin.index());
    let Some(json) = doc.as_json().skins.get(skin.index()) else {
        return Err(ctx.invalid((path, "the skin does not exist".into())));
    };
    let joints: Vec<usize> = json.joints.iter().map(|j| j.value()).collect();
    let inverse_bind: Option<Vec<Mat4>> = match json.inverse_bind_matrices {
        None => None,
        Some(i) => {
            let ipath = format!("{path}.inverseBindMatrices");
            let acc = doc.accessors().nth(i.value()).ok_or_else(|| {
                ctx.invalid((ipath.clone(), format!("accessor {} does not exist", i.value())))
            })?;
            let (m, _) = read_floats(&acc, buffers, &[Dimensions::Mat4]).map_err(|e| ctx.invalid(e))?;
            if m.len() / 16 < joints.len() {
                return Err(ctx.invalid((
                    ipath,
                    format!("{} matrices for {} joints: one per joint needed", m.len() / 16, joints.len()),
                )));
            }
            if let Some(k) = m.iter().position(|x| !x.is_finite()) {
                return Err(ctx.invalid((ipath, format!("matrix {} is not finite", k / 16))));
            }
            Some(m.chunks_exact(16).map(Mat4::from_cols_slice).collect())
        }
    };
    let matrices = joints
        .iter()
        .enumerate()
        .map(|(j, &node)| {
            let world = worlds.get(node).copied().flatten().ok_or_else(|| {
                ctx.invalid((
                    format!("{path}.joints[{j}]"),
                    format!(
                        "nodes[{node}] has no world transform (it is in a cycle, or a transform on its path is \
                         not finite or not a rotation)"
                    ),
                ))
            })?;
            Ok(match &inverse_bind {
                Some(m) => world * m[j],
                None => world,
            })
        })
        .collect::<Result<Vec<_>, SceneError>>()?;
    Ok(JointMatrices { path, matrices })
}
