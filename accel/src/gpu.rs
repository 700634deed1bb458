//! GPU-ready buffers: `#[repr(C)]`, [`bytemuck::Pod`], sizes asserted at compile time.
//!
//! A WGSL traversal binds three storage buffers, all produced by [`crate::Bvh`]:
//!
//! | buffer | element | bytes | from |
//! |---|---|---|---|
//! | nodes | [`GpuCwbvhNode`] | 80 | [`crate::Bvh::gpu_nodes`] |
//! | triangles | [`GpuTriangle`] | 48 | [`crate::Bvh::gpu_triangles`] |
//! | triangle ids | `u32` | 4 | [`crate::Bvh::triangle_ids`] |
//!
//! Triangles are stored in **leaf order** ("direct layout"): a leaf's primitive slots index the
//! triangle buffer directly, with no indirection through an index buffer during traversal; the
//! caller's triangle id is in [`GpuTriangle::id`] (and, equivalently, in the ids buffer at the
//! same slot). With spatial pre-splits a triangle may occupy several slots.

use bytemuck::{Pod, Zeroable};
use obvhs::cwbvh::node::CwBvhNode;

/// One compressed wide BVH8 node (Ylitie, Karras & Laine 2017, section 3.1), 80 bytes.
///
/// Field for field the same bytes as obvhs's [`CwBvhNode`] (checked by a unit test), declared
/// here with plain arrays so that the layout a shader sees is written down in this crate.
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0 | `p: [f32; 3]` | origin of the child quantisation grid (min corner of the node) |
/// | 12 | `e: [u8; 3]` | per-axis grid scale as a biased exponent: `scale = bitcast<f32>(e << 23)` |
/// | 15 | `imask: u8` | bit *i* set: child slot *i* is an internal node |
/// | 16 | `child_base_idx: u32` | index of the first internal child in the node buffer |
/// | 20 | `primitive_base_idx: u32` | index of the first triangle slot of this node's leaves |
/// | 24 | `child_meta: [u8; 8]` | per slot: 0 = empty; internal = `0b001` ⋅ (24 + slot); leaf = unary triangle count (high 3 bits) ⋅ offset from `primitive_base_idx` (low 5 bits) |
/// | 32 | `child_min_x`…`child_max_z: [[u8; 8]; 6]` | quantised child boxes, order min x, max x, min y, max y, min z, max z (obvhs interleaves min and max, a deviation from the paper) |
///
/// A child box in world space is `p + scale · q` per axis. Internal children are stored
/// contiguously from `child_base_idx` in slot order (`child_base_idx + popcount(imask & ((1 << slot) − 1))`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct GpuCwbvhNode {
    /// Origin of the quantisation grid.
    pub p: [f32; 3],
    /// Per-axis scale exponents (`f32` exponent bits).
    pub e: [u8; 3],
    /// Internal-child mask.
    pub imask: u8,
    /// First internal child node.
    pub child_base_idx: u32,
    /// First triangle slot.
    pub primitive_base_idx: u32,
    /// Per-slot metadata (see the table above).
    pub child_meta: [u8; 8],
    /// Quantised child box minima, x.
    pub child_min_x: [u8; 8],
    /// Quantised child box maxima, x.
    pub child_max_x: [u8; 8],
    /// Quantised child box minima, y.
    pub child_min_y: [u8; 8],
    /// Quantised child box maxima, y.
    pub child_max_y: [u8; 8],
    /// Quantised child box minima, z.
    pub child_min_z: [u8; 8],
    /// Quantised child box maxima, z.
    pub child_max_z: [u8; 8],
}

const _: () = assert!(size_of::<GpuCwbvhNode>() == 80);
const _: () = assert!(size_of::<CwBvhNode>() == 80);
const _: () = assert!(align_of::<GpuCwbvhNode>() == align_of::<CwBvhNode>());

/// One triangle in leaf order, 48 bytes: three vertices padded to 16 bytes (WGSL's `vec3<f32>`
/// alignment), with the caller's triangle id in the first pad.
///
/// | offset | field |
/// |---|---|
/// | 0 | `v0: [f32; 3]` |
/// | 12 | `id: u32` — index of the triangle in the input of [`crate::Bvh::build`] |
/// | 16 | `v1: [f32; 3]` |
/// | 28 | `reserved1: u32` (0) |
/// | 32 | `v2: [f32; 3]` |
/// | 44 | `reserved2: u32` (0) |
///
/// The vertices are the input's, unchanged, so a shader can run the same Möller–Trumbore test
/// as [`crate::intersect_triangle`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct GpuTriangle {
    /// First vertex.
    pub v0: [f32; 3],
    /// The triangle's index in the builder's input.
    pub id: u32,
    /// Second vertex.
    pub v1: [f32; 3],
    /// Zero; free for a future material or flag word.
    pub reserved1: u32,
    /// Third vertex.
    pub v2: [f32; 3],
    /// Zero; free for a future material or flag word.
    pub reserved2: u32,
}

const _: () = assert!(size_of::<GpuTriangle>() == 48);

impl GpuTriangle {
    /// The three vertices as `glam` vectors.
    #[inline(always)]
    pub fn vertices(&self) -> [glam::Vec3; 3] {
        [self.v0.into(), self.v1.into(), self.v2.into()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mirror must read the same bytes as obvhs's node, field by field.
    #[test]
    fn mirror_agrees_with_obvhs_node() {
        let bytes: Vec<u8> = (0..80u8).map(|i| i.wrapping_mul(37).wrapping_add(11)).collect();
        let ours: GpuCwbvhNode = bytemuck::pod_read_unaligned(&bytes);
        let theirs: CwBvhNode = bytemuck::pod_read_unaligned(&bytes);
        assert_eq!(ours.p, theirs.p.to_array());
        assert_eq!(ours.e, theirs.e);
        assert_eq!(ours.imask, theirs.imask);
        assert_eq!(ours.child_base_idx, theirs.child_base_idx);
        assert_eq!(ours.primitive_base_idx, theirs.primitive_base_idx);
        assert_eq!(ours.child_meta, theirs.child_meta);
        assert_eq!(ours.child_min_x, theirs.child_min_x);
        assert_eq!(ours.child_max_x, theirs.child_max_x);
        assert_eq!(ours.child_min_y, theirs.child_min_y);
        assert_eq!(ours.child_max_y, theirs.child_max_y);
        assert_eq!(ours.child_min_z, theirs.child_min_z);
        assert_eq!(ours.child_max_z, theirs.child_max_z);
    }
}
