//! # furnace-accel
//!
//! Ray-triangle acceleration for furnace: a bounding volume hierarchy over a plain triangle soup,
//! closest-hit and any-hit (shadow) queries with an optional alpha-mask callback, robust
//! ray-origin offsets, and the BVH as GPU-ready `Pod` buffers.
//!
//! ## Methods
//!
//! | part | method | paper |
//! |---|---|---|
//! | build | PLOC: parallel locally-ordered clustering over Morton-sorted boxes, then parallel reinsertion, optional spatial pre-splits | Meister & Bittner, "Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy Construction", IEEE TVCG 2018; Meister & Bittner, "Parallel Reinsertion for Bounding Volume Hierarchy Optimization", Eurographics 2018 |
//! | tree | compressed wide BVH8 (CWBVH): 8 children per 80-byte node, child boxes quantised to 8 bits on a per-node grid, octant-ordered traversal | Ylitie, Karras & Laine, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017 |
//! | triangle | two-sided Möller–Trumbore in `f32` ([`intersect_triangle`]) | Möller & Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection", JGT 1997 |
//! | offsets | integer-ULP offset along the normal ([`offset_ray_origin`]) | Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems, ch. 6, 2019 |
//!
//! Building and the traversal order are [obvhs](https://docs.rs/obvhs) 0.4's (CWBVH trees of
//! up to 16 384 nodes are traversed with this crate's own child-box test over nodes decoded at
//! build time, see `BENCHMARKS.md`); this crate adds the
//! triangle storage, stable ids, degenerate-input handling, masks, a fix for obvhs's absolute
//! `1e-4` node-entry cut-off (see [`Bvh::closest_hit`] and the source of `Bvh::obvhs_ray`),
//! and the documented GPU layout.
//!
//! ## Input and ids
//!
//! The input is `&[[Vec3; 3]]` (or positions + index triples via [`Bvh::from_indexed`]),
//! independent of any scene format. A hit reports the triangle's index in that input. Triangles
//! with a non-finite vertex or zero area are not put in the tree (no ray hits them) but keep
//! their ids; [`Bvh::skipped_count`] counts them.
//!
//! ## Presets
//!
//! [`BuildQuality`] names obvhs's six presets; [`BuildQuality::for_triangle_count`] picks one
//! when [`BuildOptions::quality`] is `None`: `VerySlow` (spatial splits, every node reinserted:
//! the best trees) up to 300 k triangles, `Medium` up to 3 M, `Fast` beyond.
//!
//! ## GPU buffers
//!
//! Three storage buffers, all `#[repr(C)]` + [`bytemuck::Pod`] with compile-time size checks
//! (byte layouts in [`GpuCwbvhNode`] and [`GpuTriangle`]):
//!
//! * [`Bvh::gpu_nodes`] — `[GpuCwbvhNode]`, 80 bytes each, root at 0;
//! * [`Bvh::gpu_triangles`] — `[GpuTriangle]`, 48 bytes each, in leaf order (leaf slots index
//!   it directly), each carrying its input id;
//! * [`Bvh::triangle_ids`] — `[u32]`, the same ids as a separate buffer.
//!
//! ## Example
//!
//! ```
//! use furnace_accel::{Bvh, offset_ray_origin};
//! use glam::Vec3;
//!
//! // A floor and a small occluder above it.
//! let tris = [
//!     [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)],
//!     [Vec3::new(-0.1, 0.5, -0.1), Vec3::new(0.1, 0.5, -0.1), Vec3::new(0.0, 0.5, 0.1)],
//! ];
//! let bvh = Bvh::build(&tris);
//!
//! // A camera ray straight down hits the occluder first.
//! let hit = bvh.closest_hit(Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, f32::INFINITY).unwrap();
//! assert_eq!(hit.triangle, 1);
//! assert!((hit.t - 1.5).abs() < 1e-6);
//!
//! // A shadow ray from the floor towards a light straight up is blocked...
//! let p = offset_ray_origin(Vec3::ZERO, Vec3::Y);
//! assert!(bvh.occluded(p, Vec3::Y, 10.0));
//! // ...unless an alpha mask says the occluder is cut out there.
//! assert!(!bvh.occluded_masked(p, Vec3::Y, 10.0, |id, _uv| id != 1));
//! ```

mod build;
mod bvh;
mod convert;
mod gpu;
mod instances;
mod offset;
mod traverse;
mod triangle;

pub use bvh::{BuildOptions, BuildQuality, Bvh, CULL_SLACK, Hit, Layout, MAX_BUILD_COORDINATE};
pub use gpu::{GpuCwbvhNode, GpuTriangle};
pub use instances::{AccelBytes, InstanceHit, SceneAccel, TlasNode, TwoLevel};
pub use offset::{
    FLOAT_SCALE, INT_SCALE, ORIGIN, offset_ray_origin, offset_ray_origin_scaled, offset_scale,
    offset_scale_of_bounds,
};
pub use triangle::{TriangleHit, intersect_triangle};
