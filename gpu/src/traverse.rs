//! Rust side of the WGSL CWBVH traversal ([`crate::wgsl::TRAVERSE`]): the buffers it binds, the
//! declarations a shader adds to use it, and the stack-size knob the overflow test turns.
//!
//! A shader that traces rays composes [`crate::wgsl::TRAVERSE`] (or [`module_with_stack_size`])
//! with its own code, which must declare the two buffers (see [`bindings`]) and the alpha-mask
//! callback `fn hit_filter(triangle_id: u32, u: f32, v: f32) -> bool`; then it calls
//! `trace_closest(origin, dir, t_max) -> Hit`, `trace_any(origin, dir, t_max) -> bool` and
//! `offset_ray_origin(p, n)`. The top of `traverse.wgsl` documents them, and the stack
//! overflow behaviour (a linear sweep over the nodes: slower, never a lost hit).
//!
//! ```no_run
//! # fn main() -> Result<(), furnace_gpu::GpuError> {
//! use furnace_gpu::{GpuContext, AdapterChoice, traverse, wgsl};
//! let ctx = GpuContext::new(&AdapterChoice::Best)?;
//! let tris = [[glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y]];
//! let bvh = furnace_accel::Bvh::build(&tris);
//! let buffers = traverse::BvhBuffers::new(&bvh, ctx.max_storage_binding())?;
//! let src = wgsl::compose(&[
//!     &traverse::bindings(0, 3),
//!     &traverse::one_level(),
//!     "fn hit_filter(id: u32, u: f32, v: f32) -> bool { return true; }",
//!     "@compute @workgroup_size(64) fn main() { /* trace_closest(...) */ }",
//! ]);
//! // `src` becomes a compute pipeline whose group 0 binds `buffers.extra()` at 3 and 4.
//! let _ = (src, buffers.extra());
//! # Ok(()) }
//! ```

use furnace_accel::{Bvh, GpuCwbvhNode, GpuTriangle, Layout, TlasNode, TwoLevel};

use crate::GpuError;
use crate::shared::{Binding, BindingTable, GpuStruct, Member, WgslType, wgsl_struct};
use std::mem::offset_of;

/// Node groups the WGSL traversal stack holds (`TRV_STACK_SIZE` in `traverse.wgsl`) at most: one
/// per tree level below the root, so trees up to this depth never overflow (deeper ones finish
/// with the fallback sweep, same hits). Half of obvhs's (and `furnace-accel`'s CPU) 32: the
/// stack is per-invocation private memory, a smaller one makes the megakernel faster
/// (BENCHMARKS.md), and real scenes stay below depth 11 (10^7 triangles). Shallower trees get a stack of their own depth ([`stack_size_for`]).
pub const DEFAULT_STACK_SIZE: u32 = 16;

/// The line of `traverse.wgsl` that declares a stack of `size` node groups (the module's own is
/// `stack_line(DEFAULT_STACK_SIZE)`; [`module_with_stack_size`] rewrites it).
fn stack_line(size: u32) -> String {
    format!("const TRV_STACK_SIZE: u32 = {size}u;")
}

/// `u32` words per node (80 bytes).
pub const NODE_WORDS: usize = size_of::<GpuCwbvhNode>() / 4;
/// `u32` words per triangle (48 bytes).
pub const TRIANGLE_WORDS: usize = size_of::<GpuTriangle>() / 4;

/// The traversal stack for a tree of `depth` node levels ([`Bvh::depth`]): `depth − 1` node
/// groups (the most the traversal pushes, so it never overflows), at least 1, at most
/// [`DEFAULT_STACK_SIZE`]. The stack is per-invocation private memory, and its size, not only
/// its use, costs: a shallow tree's kernel is faster with a stack of its depth (BENCHMARKS.md).
pub fn stack_size_for(depth: usize) -> u32 {
    u32::try_from(depth.saturating_sub(1)).unwrap_or(u32::MAX).clamp(1, DEFAULT_STACK_SIZE)
}

/// `source`, a shader that composes [`crate::wgsl::TRAVERSE`] unchanged, with a traversal stack
/// of `size` node groups instead of [`DEFAULT_STACK_SIZE`]: a smaller stack uses less private
/// memory per invocation, and a tiny one makes ordinary trees overflow (how the tests exercise
/// the fallback).
///
/// # Panics
/// If `size` is 0, or `source` lacks the module's stack-size line.
pub fn with_stack_size(source: &str, size: u32) -> String {
    assert!(size > 0, "the traversal stack needs at least one entry");
    let line = stack_line(DEFAULT_STACK_SIZE);
    assert!(source.contains(&line), "the shader lacks traverse.wgsl's stack-size line");
    source.replace(&line, &stack_line(size))
}

/// [`crate::wgsl::TRAVERSE`] with a traversal stack of `size` node groups ([`with_stack_size`]).
///
/// # Panics
/// If `size` is 0.
pub fn module_with_stack_size(size: u32) -> String {
    with_stack_size(&one_level(), size)
}

/// [`crate::wgsl::TRAVERSE`] as a shader without instances composes it: the one-level
/// traversal (the trace counters' blocks kept; the two-level `INSTANCES` code and the second
/// triangle binding's `SPLIT_TRIANGLES` left out).
pub fn one_level() -> String {
    crate::wgsl::select(crate::wgsl::TRAVERSE, |name| name != "INSTANCES" && name != "SPLIT_TRIANGLES")
}

/// The declarations of the two storage buffers the traversal reads, at `@group(group)`,
/// bindings `first` (nodes) and `first + 1` (triangles), for the composing shader.
pub fn bindings(group: u32, first: u32) -> String {
    declarations() + &BindingTable::new(group, first, binding_list()).wgsl()
}

/// The WGSL declarations of the two buffers' element structs, `CwbvhNode` and `Triangle`,
/// generated from furnace-accel's [`GpuCwbvhNode`] and [`GpuTriangle`] (composed by
/// [`bindings`]).
pub fn declarations() -> String {
    wgsl_struct::<GpuCwbvhNode>(false) + &wgsl_struct::<GpuTriangle>(false) + &constants_wgsl()
}

/// The traversal's constants shared with furnace-accel, defined there once: the culling slack
/// and `offset_ray_origin`'s origin and scales (printed exactly: Rust's shortest round-trip form).
fn constants_wgsl() -> String {
    use furnace_accel::{CULL_SLACK, FLOAT_SCALE, INT_SCALE, ORIGIN};
    format!(
        "const TRV_CULL_SLACK: f32 = {CULL_SLACK:?};\nconst TRV_ORIGIN: f32 = {ORIGIN:?};\n\
         const TRV_FLOAT_SCALE: f32 = {FLOAT_SCALE:?};\nconst TRV_INT_SCALE: f32 = {INT_SCALE:?};\n"
    )
}

/// `vec2<u32>` holding eight bytes, one per child slot (slots 0–3 in `.x`, 4–7 in `.y`).
const SLOT_BYTES: WgslType = WgslType::VEC2_U32;

/// The WGSL view of furnace-accel's node: the same bytes, with the three exponent bytes and the
/// internal-child mask read as one `u32` (`e_imask`), and the per-slot byte arrays as
/// `vec2<u32>` (WGSL has no `u8`).
impl GpuStruct for GpuCwbvhNode {
    const NAME: &'static str = "CwbvhNode";
    fn members() -> Vec<Member> {
        let m = Member::new;
        vec![
            m("p", WgslType::ARRAY_F32_3, offset_of!(GpuCwbvhNode, p)),
            m("e_imask", WgslType::U32, offset_of!(GpuCwbvhNode, e)),
            m("child_base_idx", WgslType::U32, offset_of!(GpuCwbvhNode, child_base_idx)),
            m("primitive_base_idx", WgslType::U32, offset_of!(GpuCwbvhNode, primitive_base_idx)),
            m("child_meta", SLOT_BYTES, offset_of!(GpuCwbvhNode, child_meta)),
            m("child_min_x", SLOT_BYTES, offset_of!(GpuCwbvhNode, child_min_x)),
            m("child_max_x", SLOT_BYTES, offset_of!(GpuCwbvhNode, child_max_x)),
            m("child_min_y", SLOT_BYTES, offset_of!(GpuCwbvhNode, child_min_y)),
            m("child_max_y", SLOT_BYTES, offset_of!(GpuCwbvhNode, child_max_y)),
            m("child_min_z", SLOT_BYTES, offset_of!(GpuCwbvhNode, child_min_z)),
            m("child_max_z", SLOT_BYTES, offset_of!(GpuCwbvhNode, child_max_z)),
        ]
    }
}

// `e_imask` covers `e` and `imask`: the mask is the fourth byte of the word.
const _: () = assert!(offset_of!(GpuCwbvhNode, imask) == offset_of!(GpuCwbvhNode, e) + 3);

/// furnace-accel's triangle slot as the WGSL reads it.
impl GpuStruct for GpuTriangle {
    const NAME: &'static str = "Triangle";
    fn members() -> Vec<Member> {
        let m = Member::new;
        vec![
            m("v0", WgslType::VEC3_F32, offset_of!(GpuTriangle, v0)),
            m("id", WgslType::U32, offset_of!(GpuTriangle, id)),
            m("v1", WgslType::VEC3_F32, offset_of!(GpuTriangle, v1)),
            m("reserved1", WgslType::U32, offset_of!(GpuTriangle, reserved1)),
            m("v2", WgslType::VEC3_F32, offset_of!(GpuTriangle, v2)),
            m("reserved2", WgslType::U32, offset_of!(GpuTriangle, reserved2)),
        ]
    }
}

/// furnace-accel's TLAS node as the WGSL reads it (the same 32 bytes).
impl GpuStruct for TlasNode {
    const NAME: &'static str = "TlasNode";
    fn members() -> Vec<Member> {
        let m = Member::new;
        vec![
            m("min", WgslType::VEC3_F32, offset_of!(TlasNode, min)),
            m("count", WgslType::U32, offset_of!(TlasNode, count)),
            m("max", WgslType::VEC3_F32, offset_of!(TlasNode, max)),
            m("first", WgslType::U32, offset_of!(TlasNode, first)),
        ]
    }
}

crate::gpu_struct! {
    /// One instance as the traversal and the shading read it, 160 bytes: its transforms as
    /// three rows each (`row · (p, 1)` is a coordinate), the normal matrix's rows, and where its
    /// mesh's BVH lies in `bvh_nodes`.
    pub struct GpuInstance as "Instance" {
        /// World to object, row x.
        pub object_x: [f32; 4] => WgslType::VEC4_F32,
        /// World to object, row y.
        pub object_y: [f32; 4] => WgslType::VEC4_F32,
        /// World to object, row z.
        pub object_z: [f32; 4] => WgslType::VEC4_F32,
        /// Object to world, row x.
        pub world_x: [f32; 4] => WgslType::VEC4_F32,
        /// Object to world, row y.
        pub world_y: [f32; 4] => WgslType::VEC4_F32,
        /// Object to world, row z.
        pub world_z: [f32; 4] => WgslType::VEC4_F32,
        /// The normal matrix (inverse transpose of the linear part), row x (w 0).
        pub normal_x: [f32; 4] => WgslType::VEC4_F32,
        /// Row y.
        pub normal_y: [f32; 4] => WgslType::VEC4_F32,
        /// Row z.
        pub normal_z: [f32; 4] => WgslType::VEC4_F32,
        /// The mesh's root node.
        pub root: u32 => WgslType::U32,
        /// One past the mesh's last node.
        pub node_end: u32 => WgslType::U32,
        /// 1 if the transform mirrors (the front is the mesh's: the geometric normal turns).
        pub mirrors: u32 => WgslType::U32,
        /// Xored into a path ray's blend seed at this instance's triangles (0: none).
        pub seed_mix: u32 => WgslType::U32,
    }
}

const _: () = assert!(size_of::<GpuInstance>() == 160);

/// The rows of an affine transform, `(m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x)`, ….
fn rows(a: &glam::Affine3A) -> [[f32; 4]; 3] {
    let m = a.matrix3;
    let t = a.translation;
    [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z],
    ]
}

impl GpuInstance {
    /// The instance placing mesh `root..node_end` by `world_from_object` (`seed_mix` as the
    /// CPU's blend seeds take it).
    pub fn new(world_from_object: glam::Affine3A, root: u32, node_end: u32, seed_mix: u32) -> Self {
        let inverse = world_from_object.inverse();
        let normal = glam::Mat3::from(world_from_object.matrix3).inverse().transpose();
        let [object_x, object_y, object_z] = rows(&inverse);
        let [world_x, world_y, world_z] = rows(&world_from_object);
        let n = |r: glam::Vec3| [r.x, r.y, r.z, 0.0];
        let (nx, ny, nz) = (normal.row(0), normal.row(1), normal.row(2));
        Self {
            object_x,
            object_y,
            object_z,
            world_x,
            world_y,
            world_z,
            normal_x: n(nx),
            normal_y: n(ny),
            normal_z: n(nz),
            root,
            node_end,
            mirrors: u32::from(world_from_object.matrix3.determinant() < 0.0),
            seed_mix,
        }
    }
}

/// [`GpuError::TooLarge`] when a buffer of `bytes` exceeds the binding limit `max_binding`.
fn check_binding(what: &str, bytes: usize, max_binding: u64) -> Result<(), GpuError> {
    if bytes as u64 > max_binding {
        Err(GpuError::TooLarge { what: what.into(), bytes: bytes as u64, limit: max_binding })
    } else {
        Ok(())
    }
}

/// The two-level traversal's extra read-only bindings: `tlas_nodes`, `instances`.
pub fn instance_binding_list() -> Vec<Binding> {
    vec![Binding::read("tlas_nodes", "array<TlasNode>"), Binding::read("instances", "array<Instance>")]
}

/// The declarations of the two-level traversal's structs (`TlasNode`, `Instance`).
pub fn instance_declarations() -> String {
    wgsl_struct::<TlasNode>(false) + &wgsl_struct::<GpuInstance>(false)
}

/// A scene's instances as the words of the WGSL two-level traversal: the TLAS and the instances
/// (every mesh's CWBVH goes into the [`BvhBuffers`] [`InstanceBuffers::new`] returns beside).
#[derive(Debug, Clone, PartialEq)]
pub struct InstanceBuffers {
    /// `tlas_nodes`: 8 words per node, root first.
    pub tlas: Vec<u32>,
    /// `instances`: [`GpuInstance`]s.
    pub instances: Vec<GpuInstance>,
    /// The deepest mesh BVH ([`Bvh::depth`]).
    pub depth: usize,
}

impl InstanceBuffers {
    /// Packs `two` (built over meshes only: its world part, if any, must be placed as an instance
    /// of its own) with each instance's `world_from_object` and blend-seed mix, checking each
    /// buffer against `max_binding` bytes: every mesh's CWBVH in one node and one triangle buffer
    /// (nodes and triangle slots renumbered, ids the caller's), and the TLAS and instances.
    ///
    /// # Errors
    /// [`GpuError::TooLarge`] for a buffer beyond `max_binding`.
    ///
    /// # Panics
    /// If `two` has world triangles outside its meshes, or the instance lists differ in length.
    pub fn new(
        two: &TwoLevel,
        placements: &[(glam::Affine3A, u32)],
        max_binding: u64,
    ) -> Result<(BvhBuffers, Self), GpuError> {
        assert!(two.world().is_none(), "place the world triangles as an instance of their own");
        let mut nodes: Vec<GpuCwbvhNode> = Vec::new();
        let mut tris: Vec<GpuTriangle> = Vec::new();
        let mut ranges = Vec::new();
        let mut depth = 0;
        for (bvh, first) in two.meshes() {
            let (node_base, tri_base) = (nodes.len() as u32, tris.len() as u32);
            nodes.extend(bvh.gpu_nodes().iter().map(|n| GpuCwbvhNode {
                child_base_idx: n.child_base_idx + node_base,
                primitive_base_idx: n.primitive_base_idx + tri_base,
                ..*n
            }));
            tris.extend(bvh.gpu_triangles().iter().map(|t| GpuTriangle { id: t.id + first, ..*t }));
            ranges.push((node_base, nodes.len() as u32));
            depth = depth.max(bvh.depth());
        }
        let placed: Vec<(u32, glam::Affine3A)> = two.placements().collect();
        assert_eq!(placed.len(), placements.len(), "one transform per instance");
        let instances: Vec<GpuInstance> = placed
            .iter()
            .zip(placements)
            .map(|(&(mesh, _), &(world, seed_mix))| {
                let (root, end) = ranges[mesh as usize];
                GpuInstance::new(world, root, end, seed_mix)
            })
            .collect();
        let bvh = BvhBuffers::from_parts(&nodes, &tris, max_binding)?;
        let what = format!("the instance buffer ({} instances)", instances.len());
        check_binding(&what, size_of_val(instances.as_slice()), max_binding)?;
        let tlas: Vec<u32> = if two.tlas_nodes().is_empty() {
            // No instance has a box: a root leaf of instance 0 (a zero instance when there is
            // none, whose zero direction no traversal takes).
            bytemuck::cast_slice(&[TlasNode { min: [0.0; 3], count: 1, max: [0.0; 3], first: 0 }]).to_vec()
        } else {
            bytemuck::cast_slice(two.tlas_nodes()).to_vec()
        };
        let instances = if instances.is_empty() { vec![bytemuck::Zeroable::zeroed()] } else { instances };
        Ok((bvh, Self { tlas, instances, depth }))
    }

    /// The two extra buffers in binding order (TLAS nodes, instances).
    pub fn extra(&self) -> [&[u32]; 2] {
        [&self.tlas, bytemuck::cast_slice(&self.instances)]
    }
}

/// The traversal's two read-only storage bindings: `bvh_nodes`, `bvh_triangles`.
pub fn binding_list() -> Vec<Binding> {
    vec![Binding::read("bvh_nodes", "array<CwbvhNode>"), Binding::read("bvh_triangles", "array<Triangle>")]
}

/// The second triangle binding of a tree whose triangle slots do not fit one
/// ([`BvhBuffers::is_split`]; composed with `SPLIT_TRIANGLES`), bound right after
/// [`binding_list`]'s.
pub fn split_binding() -> Binding {
    Binding::read("bvh_triangles_high", "array<Triangle>")
}

/// A CWBVH as the `u32` words of the two storage buffers of the WGSL traversal: the bytes of
/// [`Bvh::gpu_nodes`] and [`Bvh::gpu_triangles`], unchanged (both are `Pod` with 4-byte
/// fields, so the words are their little-endian bytes: exactly what a storage buffer holds).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BvhBuffers {
    /// `bvh_nodes`: [`NODE_WORDS`] words per node, root first.
    pub nodes: Vec<u32>,
    /// `bvh_triangles`: [`TRIANGLE_WORDS`] words per triangle slot, in leaf order.
    pub triangles: Vec<u32>,
    /// `bvh_triangles_high`: the slots after `triangles`' when they do not fit one binding
    /// (empty otherwise; the traversal then composes no second binding, `SPLIT_TRIANGLES`).
    pub triangles_high: Vec<u32>,
}

impl BvhBuffers {
    /// Packs `bvh` and checks each buffer against `max_binding` bytes (pass
    /// [`crate::GpuContext::max_storage_binding`]).
    ///
    /// A tree with no triangle becomes one all-zero node (no child, so no ray hits anything)
    /// and one zero triangle, because zero-sized bindings are invalid; the traversal never
    /// reaches that triangle.
    ///
    /// # Errors
    /// [`GpuError::TooLarge`] when the node or triangle buffer exceeds `max_binding` (the
    /// scene needs a device with a larger limit, or to be split).
    ///
    /// # Panics
    /// If `bvh` was built with [`Layout::Bvh2`] but has triangles: the GPU traverses CWBVHs only
    /// (a programming error, not a property of the scene).
    pub fn new(bvh: &Bvh, max_binding: u64) -> Result<Self, GpuError> {
        let tris = bvh.gpu_triangles();
        assert!(
            bvh.layout() == Layout::Cwbvh || tris.is_empty(),
            "furnace-gpu traverses CWBVHs: build the Bvh with Layout::Cwbvh"
        );
        Self::from_parts(bvh.gpu_nodes(), tris, max_binding)
    }

    /// The buffers of CWBVH `nodes` and their triangle slots `tris` (one tree's, or several
    /// trees' renumbered into one), checked as [`BvhBuffers::new`] checks them.
    fn from_parts(nodes: &[GpuCwbvhNode], tris: &[GpuTriangle], max_binding: u64) -> Result<Self, GpuError> {
        check_binding(
            &format!("the BVH node buffer ({} nodes)", nodes.len()),
            size_of_val(nodes),
            max_binding,
        )?;
        // Triangle slots beyond one binding go to a second one: the triangle buffer is the
        // largest per triangle (48 bytes), and a 4 GiB binding holds 8.9·10⁷ of them.
        let per_binding = (max_binding / size_of::<GpuTriangle>() as u64).max(1) as usize;
        let (low, high) = tris.split_at(tris.len().min(per_binding));
        let what = format!("the BVH triangle buffer ({} triangle slots, in two bindings)", tris.len());
        check_binding(&what, size_of_val(low), max_binding)?;
        check_binding(&what, size_of_val(high), max_binding)?;
        let nodes: Vec<u32> =
            if nodes.is_empty() { vec![0; NODE_WORDS] } else { bytemuck::cast_slice(nodes).to_vec() };
        let triangles: Vec<u32> =
            if low.is_empty() { vec![0; TRIANGLE_WORDS] } else { bytemuck::cast_slice(low).to_vec() };
        Ok(BvhBuffers { nodes, triangles, triangles_high: bytemuck::cast_slice(high).to_vec() })
    }

    /// Number of nodes in [`Self::nodes`].
    pub fn node_count(&self) -> usize {
        self.nodes.len() / NODE_WORDS
    }

    /// Number of triangle slots in [`Self::triangles`] and [`Self::triangles_high`].
    pub fn triangle_count(&self) -> usize {
        (self.triangles.len() + self.triangles_high.len()) / TRIANGLE_WORDS
    }

    /// Whether the triangle slots take two bindings (`SPLIT_TRIANGLES`).
    pub fn is_split(&self) -> bool {
        !self.triangles_high.is_empty()
    }

    /// Both buffers in binding order (nodes, triangles), e.g. for the test kernels of `furnace-tests`
    /// with [`bindings`]`(0, 3)` (a split tree's second triangle binding is
    /// [`Self::triangles_high`], bound after them with [`split_binding`]).
    pub fn extra(&self) -> [&[u32]; 2] {
        [&self.nodes, &self.triangles]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn packs_the_bytes_of_accel_buffers() {
        let tris = [[Vec3::ZERO, Vec3::X, Vec3::Y], [Vec3::Z, Vec3::X + Vec3::Z, Vec3::Y + Vec3::Z]];
        let bvh = Bvh::build(&tris);
        let b = BvhBuffers::new(&bvh, u64::MAX).unwrap();
        assert_eq!(b.node_count(), bvh.gpu_nodes().len());
        assert_eq!(b.triangle_count(), bvh.gpu_triangles().len());
        let bytes: &[u8] = bytemuck::cast_slice(&b.nodes);
        assert_eq!(bytes, bytemuck::cast_slice::<_, u8>(bvh.gpu_nodes()));
        // Word 3 of a triangle is its id.
        assert_eq!(b.triangles[3], bvh.gpu_triangles()[0].id);
    }

    #[test]
    fn empty_tree_is_one_zero_node() {
        let bvh = Bvh::build(&[]);
        let b = BvhBuffers::new(&bvh, u64::MAX).unwrap();
        assert_eq!(b.nodes, vec![0; NODE_WORDS]);
        assert_eq!(b.triangles, vec![0; TRIANGLE_WORDS]);
    }

    #[test]
    fn too_large_names_the_buffer_and_limit() {
        // Four small triangles: one node (80 bytes), four triangle slots (192 bytes).
        let tris: Vec<[Vec3; 3]> =
            (0..4).map(|k| [Vec3::ZERO, Vec3::X, Vec3::Y].map(|v| v + Vec3::Z * k as f32)).collect();
        let bvh = Bvh::build(&tris);
        assert_eq!((bvh.gpu_nodes().len(), bvh.gpu_triangles().len()), (1, 4));
        match BvhBuffers::new(&bvh, 40).unwrap_err() {
            GpuError::TooLarge { bytes: 80, limit: 40, what } => assert!(what.contains("node"), "{what}"),
            e => panic!("unexpected {e:?}"),
        }
        // 48-byte slots: a 100-byte binding holds two, the other two go to the second binding;
        // an 80-byte one holds one, and the other three (144 bytes) fit no binding.
        let split = BvhBuffers::new(&bvh, 100).unwrap();
        assert!(split.is_split());
        assert_eq!(
            (split.triangles.len(), split.triangles_high.len()),
            (2 * TRIANGLE_WORDS, 2 * TRIANGLE_WORDS)
        );
        assert_eq!(split.triangle_count(), 4);
        match BvhBuffers::new(&bvh, 80).unwrap_err() {
            GpuError::TooLarge { bytes: 144, limit: 80, what } => {
                assert!(what.contains("triangle"), "{what}")
            }
            e => panic!("unexpected {e:?}"),
        }
        assert!(!BvhBuffers::new(&bvh, 192).unwrap().is_split());
    }

    /// One group per level below the root; a root alone still gets one entry; deep trees are
    /// capped.
    #[test]
    fn stack_size_follows_the_depth() {
        assert_eq!(stack_size_for(0), 1);
        assert_eq!(stack_size_for(1), 1);
        assert_eq!(stack_size_for(4), 3);
        assert_eq!(stack_size_for(17), 16);
        assert_eq!(stack_size_for(100), DEFAULT_STACK_SIZE);
    }

    #[test]
    fn stack_size_rewrites_one_line() {
        let s = module_with_stack_size(2);
        assert!(s.contains("const TRV_STACK_SIZE: u32 = 2u;"));
        assert_eq!(s.matches("TRV_STACK_SIZE: u32").count(), 1);
    }
}
