//! A primitive posed before it is placed: morph targets (glTF 2.0 §3.7.2.2), then skinning
//! (§3.7.3), on the attributes read from the file.
//!
//! * **Morph targets**: position, normal and tangent = base + Σᵢ wᵢ · targetᵢ, over the targets
//!   with a non-zero weight; a target without an attribute adds nothing to it. Target accessors
//!   are read as any accessor (sparse ones included), one value per vertex.
//! * **Skinning** (linear blend): each vertex's matrix M = Σₖ wₖ · J[jointₖ] / Σₖ wₖ over the
//!   JOINTS_n / WEIGHTS_n sets (n = 0, 1, …), J the skin's joint matrices
//!   ([`JointMatrices`]: world · inverse bind); positions by M, normals by M's inverse
//!   transpose, tangents by M (their handedness flipped where M mirrors). The result is in world
//!   space. Weights that do not sum to 1 are normalised; a joint of weight 0 is not read (its
//!   index may be anything).

use super::Attributes;
use crate::accessor::read_floats;
use crate::error::SceneError;
use crate::load::context::Ctx;
use crate::load::skin::JointMatrices;
use glam::{Mat3, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};

/// How a node poses its mesh's primitives.
pub(in crate::load) struct Posing<'a> {
    /// The index of the node's mesh.
    pub(in crate::load) mesh: usize,
    /// The morph weights (empty: every weight 0, the base shape).
    pub(in crate::load) weights: &'a [f32],
    /// The node's skin's joint matrices (`None`: not skinned).
    pub(in crate::load) skin: Option<&'a JointMatrices>,
    /// The node's world transform: places a skinned vertex whose weights are all 0.
    pub(in crate::load) node_world: Mat4,
}

/// One JOINTS_n / WEIGHTS_n pair: 4 joint indices and 4 weights per vertex.
pub(super) struct SkinSet {
    joints: Vec<f32>,
    weights: Vec<f32>,
}

/// The JOINTS_n / WEIGHTS_n sets of `prim` (JSON path `ppath`), n = 0, 1, … while the primitive
/// has either; `read` reads one attribute (VEC4, one per vertex) by its accessor and name.
/// JOINTS must be unnormalised unsigned bytes or shorts, and each JOINTS_n needs its WEIGHTS_n.
pub(super) fn read_skin_sets(
    ctx: &Ctx<'_>,
    prim: &gltf::Primitive<'_>,
    ppath: &str,
    mut read: impl FnMut(Option<gltf::Accessor<'_>>, &str) -> Result<Option<Vec<f32>>, SceneError>,
) -> Result<Vec<SkinSet>, SceneError> {
    let mut sets = Vec::new();
    for n in 0u32.. {
        let (ja, wa) = (prim.get(&gltf::Semantic::Joints(n)), prim.get(&gltf::Semantic::Weights(n)));
        let (jname, wname) = (format!("JOINTS_{n}"), format!("WEIGHTS_{n}"));
        match (&ja, &wa) {
            (None, None) => break,
            (Some(_), None) | (None, Some(_)) => {
                let (has, lacks) = if ja.is_some() { (&jname, &wname) } else { (&wname, &jname) };
                return Err(ctx.invalid((
                    format!("{ppath}.attributes.{has}"),
                    format!("the primitive has {has} but no {lacks}"),
                )));
            }
            (Some(j), Some(_)) => {
                if j.normalized() || !matches!(j.data_type(), DataType::U8 | DataType::U16) {
                    return Err(ctx.invalid((
                        format!("{ppath}.attributes.{jname}"),
                        format!(
                            "accessors[{}] is {:?}{}: joint indices are unnormalised unsigned bytes or shorts",
                            j.index(),
                            j.data_type(),
                            if j.normalized() { " normalised" } else { "" }
                        ),
                    )));
                }
            }
        }
        let joints = read(ja, &jname)?.unwrap_or_default();
        let weights = read(wa, &wname)?.unwrap_or_default();
        sets.push(SkinSet { joints, weights });
    }
    Ok(sets)
}

/// Adds the morph targets of `prim` (JSON path `ppath`) weighted by `weights` to `a`'s
/// positions, normals and tangents (those it holds). A target accessor of the wrong type or
/// count, a non-finite weight or a non-finite result is an error naming the target.
pub(super) fn morph(
    ctx: &Ctx<'_>,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    (mesh, prim): (usize, &gltf::Primitive<'_>),
    ppath: &str,
    weights: &[f32],
    a: &mut Attributes,
) -> Result<(), SceneError> {
    let Some(targets) = doc
        .as_json()
        .meshes
        .get(mesh)
        .and_then(|m| m.primitives.get(prim.index()))
        .and_then(|p| p.targets.as_ref())
    else {
        return Ok(());
    };
    let nverts = a.positions.len() / 3;
    if nverts == 0 {
        return Ok(());
    }
    for (i, target) in targets.iter().enumerate() {
        let w: f32 = weights.get(i).copied().unwrap_or(0.0);
        if w == 0.0 {
            continue;
        }
        if !w.is_finite() {
            return Err(ctx.invalid((
                format!("{ppath}.targets[{i}]"),
                format!("its weight is {w}: morph weights must be finite"),
            )));
        }
        let attributes = [
            (target.positions, Some(&mut a.positions), "POSITION"),
            (target.normals, a.normals.as_mut(), "NORMAL"),
            (target.tangents, a.tangents.as_mut(), "TANGENT"),
        ];
        for (acc, values, name) in attributes {
            let (Some(acc), Some(values)) = (acc, values) else { continue };
            let path = format!("{ppath}.targets[{i}].{name}");
            let acc = doc.accessors().nth(acc.value()).ok_or_else(|| {
                ctx.invalid((path.clone(), format!("accessor {} does not exist", acc.value())))
            })?;
            let (d, _) = read_floats(&acc, buffers, &[Dimensions::Vec3]).map_err(|e| ctx.invalid(e))?;
            if d.len() / 3 != nverts {
                return Err(ctx.invalid((
                    path,
                    format!("count {} differs from the primitive's vertex count {nverts}", d.len() / 3),
                )));
            }
            // Tangents are VEC4 (xyz and the handedness); their displacements are VEC3.
            let width = values.len() / nverts;
            for (v, d) in values.chunks_exact_mut(width).zip(d.chunks_exact(3)) {
                for c in 0..3 {
                    v[c] += w * d[c];
                }
            }
        }
    }
    if let Some(i) = a.positions.iter().position(|x| !x.is_finite()) {
        return Err(ctx.invalid((
            format!("{ppath}.targets"),
            format!("vertex {} is not finite once the morph targets are added", i / 3),
        )));
    }
    Ok(())
}

/// Skins `a` by `skin` (see the module's documentation): positions, normals and tangents in
/// world space, and which vertices' matrices mirror. `false` (nothing changed, with a warning)
/// when the primitive has no JOINTS_0: it is placed by its node as an unskinned one. A vertex
/// whose weights are all 0 is placed by `node_world`, with a warning. A negative or non-finite
/// weight, or a joint index (of a non-zero weight) beyond the skin's joints, is an error naming
/// the attribute and the vertex.
pub(super) fn skin(
    ctx: &mut Ctx<'_>,
    skin: &JointMatrices,
    a: &mut Attributes,
    ppath: &str,
    node_world: Mat4,
) -> Result<bool, SceneError> {
    if a.skin.is_empty() {
        ctx.warn(
            ppath,
            format!(
                "the node has a skin ({}) but the primitive has no JOINTS_0 and WEIGHTS_0: placed by the \
                 node's transform, unskinned",
                skin.path
            ),
        );
        return Ok(false);
    }
    let nverts = a.positions.len() / 3;
    let mut mirrored = vec![false; nverts];
    let mut unweighted = 0usize;
    for v in 0..nverts {
        let mut m = Mat4::ZERO;
        let mut sum = 0.0f32;
        for (n, set) in a.skin.iter().enumerate() {
            for k in 4 * v..4 * v + 4 {
                let w = set.weights[k];
                if w == 0.0 {
                    continue;
                }
                if !(w.is_finite() && w > 0.0) {
                    return Err(ctx.invalid((
                        format!("{ppath}.attributes.WEIGHTS_{n}"),
                        format!("vertex {v}: weight {w} is not a finite number ≥ 0"),
                    )));
                }
                let j = set.joints[k];
                let Some(joint) = skin.matrices.get(j as usize) else {
                    return Err(ctx.invalid((
                        format!("{ppath}.attributes.JOINTS_{n}"),
                        format!(
                            "vertex {v}: joint {j} (of weight {w}) is not one of the {} joints of {}",
                            skin.matrices.len(),
                            skin.path
                        ),
                    )));
                };
                m += *joint * w;
                sum += w;
            }
        }
        let m = if sum > 0.0 {
            if sum == 1.0 { m } else { m * (1.0 / sum) }
        } else {
            unweighted += 1;
            node_world
        };
        let m3 = Mat3::from_mat4(m);
        let det = m3.determinant();
        mirrored[v] = det < 0.0;
        let p = &mut a.positions[3 * v..3 * v + 3];
        p.copy_from_slice(&m.transform_point3(Vec3::from_slice(p)).to_array());
        if let Some(normals) = a.normals.as_mut() {
            // The inverse transpose up to a positive factor: the cofactor matrix (columns
            // c₁×c₂, c₂×c₀, c₀×c₁) times the sign of the determinant; defined for singular M too.
            let (c0, c1, c2) = (m3.x_axis, m3.y_axis, m3.z_axis);
            let cof = Mat3::from_cols(c1.cross(c2), c2.cross(c0), c0.cross(c1));
            let n = &mut normals[3 * v..3 * v + 3];
            let skinned = cof * Vec3::from_slice(n) * if det < 0.0 { -1.0 } else { 1.0 };
            n.copy_from_slice(&skinned.to_array());
        }
        if let Some(tangents) = a.tangents.as_mut() {
            let t = &mut tangents[4 * v..4 * v + 4];
            let xyz = m3 * Vec3::new(t[0], t[1], t[2]);
            t[..3].copy_from_slice(&xyz.to_array());
            if det < 0.0 {
                t[3] = -t[3];
            }
        }
    }
    if unweighted > 0 {
        ctx.warn(
            ppath,
            format!("{unweighted} vertices have no joint weight: placed by the node's transform, unskinned"),
        );
    }
    if let Some(i) = a.positions.iter().position(|x| !x.is_finite()) {
        return Err(ctx.invalid((
            format!("{ppath}.attributes.POSITION"),
            format!("vertex {} skinned by {} is not finite", i / 3, skin.path),
        )));
    }
    a.mirrored = mirrored.contains(&true).then_some(mirrored);
    Ok(true)
}
