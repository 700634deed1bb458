//! Meshes stored once and placed many times: [`Instancing`] says which of a scene's triangles
//! are in world space and which are a mesh's, in its object space, placed by [`Instance`]s;
//! [`Scene::flattened`] copies every instance into world space (what a backend without a
//! two-level traversal renders, and the reference the instanced renders are tested against).

use crate::geometry::{decode_tangent, encode_tangent, oct_decode, oct_encode};
use crate::{Geometry, Scene};
use glam::{Affine3A, Mat3, Mat4, Vec3, Vec4};
use std::ops::Range;

/// One placement of a mesh: its transform, its inverse and its normal matrix, computed once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Instance {
    /// Index into [`Instancing::meshes`].
    pub mesh: u32,
    /// Object space to world space.
    pub world_from_object: Affine3A,
    /// World space to object space (the inverse): rays are traced into the mesh by it.
    pub object_from_world: Affine3A,
    /// The inverse transpose of the linear part: it carries a normal to world space with the
    /// side it faces kept (for a mirroring transform too).
    normal_matrix: Mat3,
    /// The transform mirrors (negative determinant): a tangent frame's handedness flips.
    mirrors: bool,
}

impl Instance {
    /// Mesh `mesh` placed by `world`; `None` for a transform that is not finite or not
    /// invertible (a zero scale: the instance has no area).
    pub fn new(mesh: u32, world: Mat4) -> Option<Self> {
        let world_from_object = Affine3A::from_mat4(world);
        let det = world_from_object.matrix3.determinant();
        if !world.is_finite() || !det.is_finite() || det == 0.0 {
            return None;
        }
        let object_from_world = world_from_object.inverse();
        if !object_from_world.is_finite() {
            return None;
        }
        let linear = Mat3::from(world_from_object.matrix3);
        Some(Self {
            mesh,
            world_from_object,
            object_from_world,
            normal_matrix: linear.inverse().transpose(),
            mirrors: det < 0.0,
        })
    }

    /// A point of the mesh in world space.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.world_from_object.transform_point3(p)
    }

    /// A normal of the mesh in world space, unit (zero if it vanishes).
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal_matrix * n).normalize_or_zero()
    }

    /// A tangent `(xyz, handedness)` of the mesh in world space: the direction transformed and
    /// made unit, the handedness flipped by a mirroring transform (so that the bitangent
    /// `w·cross(n, t)` still follows the texture's −v).
    #[inline]
    pub fn tangent(&self, t: Vec4) -> Vec4 {
        let xyz = self.world_from_object.transform_vector3(t.truncate()).normalize_or_zero();
        xyz.extend(if self.mirrors { -t.w } else { t.w })
    }

    /// Whether the transform mirrors (a negative determinant).
    pub fn mirrors(&self) -> bool {
        self.mirrors
    }
}

/// Which triangles of [`Scene::geometry`] are placed by instances.
///
/// Triangles `0..world_triangles` are in world space (meshes placed once, skinned or morphed
/// ones, emissive ones: each emitting instance is a light of its own, which the light list
/// holds in world space). Mesh `k` is the triangle range `meshes[k]`, after them, in the mesh's
/// object space; its vertices are its own, after the world part's. Without instances (the
/// default) every triangle is in world space and the other fields mean nothing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Instancing {
    /// Triangles before this index are in world space.
    pub world_triangles: u32,
    /// Each mesh's triangles.
    pub meshes: Vec<Range<u32>>,
    /// The placements.
    pub instances: Vec<Instance>,
}

impl Instancing {
    /// No mesh is instanced.
    pub fn is_empty(&self) -> bool {
        self.instances.is_empty()
    }

    /// The triangles the instances place, counted once per instance.
    pub fn instanced_triangles(&self) -> u64 {
        self.instances.iter().map(|i| self.meshes[i.mesh as usize].len() as u64).sum()
    }
}

impl Scene {
    /// The world-space bounds of everything the scene holds, instances included (`(+∞, −∞)`
    /// when empty).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let g = &self.geometry;
        let inst = &self.instancing;
        if inst.is_empty() {
            return g.bounds();
        }
        let empty = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let grow = |(lo, hi): (Vec3, Vec3), p: Vec3| (lo.min(p), hi.max(p));
        let of_triangles = |range: Range<u32>| {
            g.triangles[range.start as usize..range.end as usize]
                .iter()
                .flatten()
                .fold(empty, |b, &v| grow(b, g.positions[v as usize]))
        };
        let mut bounds = of_triangles(0..inst.world_triangles);
        let mesh_bounds: Vec<(Vec3, Vec3)> = inst.meshes.iter().map(|r| of_triangles(r.clone())).collect();
        for i in &inst.instances {
            let (lo, hi) = mesh_bounds[i.mesh as usize];
            if lo.x > hi.x {
                continue;
            }
            for k in 0..8 {
                let corner = Vec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                bounds = grow(bounds, i.point(corner));
            }
        }
        bounds
    }

    /// The same scene with every instance copied into world space: positions transformed,
    /// normals and tangents carried by the instance (a mirroring one rewinds its triangles, as
    /// the loader does for a mirroring node), materials and attributes copied. A scene without
    /// instancing is returned as a clone.
    pub fn flattened(&self) -> Scene {
        let mut out = self.clone();
        if self.instancing.is_empty() {
            return out;
        }
        let g = &self.geometry;
        let inst = &self.instancing;
        let world = inst.world_triangles as usize;
        let mut geo = Geometry {
            triangles: g.triangles[..world].to_vec(),
            triangle_materials: g.triangle_materials[..world].to_vec(),
            ..Geometry::default()
        };
        // The world part's vertices: those its triangles use are before any mesh's.
        let world_vertices =
            g.triangles[..world].iter().flatten().map(|&v| v as usize + 1).max().unwrap_or(0);
        let sets = g.uv_sets();
        let copy = |geo: &mut Geometry, v: usize| {
            geo.uvs.extend_from_slice(&g.uvs[v * sets..(v + 1) * sets]);
            if !g.colors.is_empty() {
                geo.colors.push(g.colors[v]);
            }
        };
        for v in 0..world_vertices {
            geo.positions.push(g.positions[v]);
            geo.normals.push(g.normals[v]);
            copy(&mut geo, v);
            if !g.tangents.is_empty() {
                geo.tangents.push(g.tangents[v]);
            }
        }
        for i in &inst.instances {
            let range = inst.meshes[i.mesh as usize].clone();
            let tris = &g.triangles[range.start as usize..range.end as usize];
            let first = tris.iter().flatten().copied().min().unwrap_or(0) as usize;
            let last = tris.iter().flatten().copied().max().map_or(0, |v| v as usize + 1);
            let base = geo.positions.len();
            for v in first..last {
                geo.positions.push(i.point(g.positions[v]));
                geo.normals.push(oct_encode(i.normal(oct_decode(g.normals[v]))));
                copy(&mut geo, v);
                if !g.tangents.is_empty() {
                    geo.tangents.push(encode_tangent(i.tangent(decode_tangent(g.tangents[v]))));
                }
            }
            let at = |v: u32| (base + v as usize - first) as u32;
            for (k, &[a, b, c]) in tris.iter().enumerate() {
                let (a, c) = if i.mirrors { (c, a) } else { (a, c) };
                geo.triangles.push([at(a), at(b), at(c)]);
                geo.triangle_materials.push(g.triangle_materials[range.start as usize + k]);
            }
        }
        out.geometry = geo;
        out.instancing = Instancing::default();
        out.instancing.world_triangles = out.geometry.triangle_count() as u32;
        out
    }
}
