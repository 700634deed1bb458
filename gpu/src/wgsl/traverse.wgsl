// furnace-gpu: traverse module — WGSL twin of `furnace-accel`'s CWBVH queries.
//
// What is twinned (Rust in accel/src/; Rust side of the buffers in gpu/src/traverse.rs):
//
// * `struct CwbvhNode` / `struct Triangle`: the bytes of `furnace_accel::GpuCwbvhNode` (80 B) and
//   `GpuTriangle` (48 B), u8 fields read from u32 words (little-endian: byte k of a word is
//   bits 8k..8k+7). Declared before this module, generated from the Rust structs
//   (`furnace_gpu::traverse::declarations`).
// * `trv_intersect_triangle`: `furnace_accel::intersect_triangle`, two-sided Möller–Trumbore,
//   the same operations in the same order (glam's `cross` and `dot`), the same accept tests.
//   A driver may fuse multiply-adds and WGSL's division is only good to 2.5 ULP, so t, u, v
//   agree with the CPU to float rounding, not bit for bit.
// * `trv_intersect_node`: accel's node test (accel/src/traverse.rs, `WideNode::intersect`,
//   itself obvhs's): `q · (extent / d) + (p − o) / d` per plane, entry clamped at 0, leave at
//   the cull distance; children hit go into the Ylitie et al. hit mask (inner children in the
//   top byte in octant order, leaf triangles in the low 24 bits).
// * `trace_closest` / `trace_any`: accel's traversal loop (node groups and triangle groups,
//   triangles of a node tested as soon as the node is), visiting nodes and triangles in the
//   same order as the CPU, culling boxes beyond `t_best · (1 + 2^-12)` like `Bvh::closest_hit`
//   (see `CULL_SLACK` in accel/src/bvh.rs), so that ties resolve the same way as on the CPU.
// * `offset_ray_origin`: `furnace_accel::offset_ray_origin` (Wächter & Binder 2019), bit-exact.
//
// What the composing shader must declare (this module declares no bindings; Rust:
// `furnace_gpu::traverse::bindings(group, first)`, which includes the two structs):
//
//   @group(G) @binding(B0) var<storage, read> bvh_nodes: array<CwbvhNode>;
//   @group(G) @binding(B1) var<storage, read> bvh_triangles: array<Triangle>;
//   with SPLIT_TRIANGLES (slots beyond one binding's size):
//   @group(G) @binding(B2) var<storage, read> bvh_triangles_high: array<Triangle>;
//   fn hit_filter(triangle_id: u32, u: f32, v: f32) -> bool { ... }  // alpha masks; true = solid
//
// `hit_filter` is called only for candidates closer than the closest accepted hit so far (for
// `trace_any`: closer than t_max), in traversal order, possibly more than once per triangle —
// what accel's `*_masked` queries promise their `mask`.
//
// Traversal stack and its overflow (the defined behaviour):
//
// The stack lives in function memory and holds TRV_STACK_SIZE node groups (8 bytes each). The
// traversal pushes at most one group per tree level, so a tree of depth ≤ TRV_STACK_SIZE never
// overflows (furnace-accel builds deeper trees too, e.g. 4000 concentric triangles; the
// parity-test scenes, up to 10^5 triangles, reach a stack depth of 7). When a push finds the stack full, the BOTTOM group (the
// shallowest, the one that would be visited last) is dropped and the ray remembers it. When
// the stack runs empty, a ray that dropped a group runs a FALLBACK: a linear sweep over every
// node of `bvh_nodes`, testing each node's leaf children against the ray (with the current cull
// distance) and their triangles. Every triangle the ray can hit lies in its leaf's box, and that
// box is tested in the sweep, so no hit is lost: the result is the same hit (same t; a tie may
// resolve to the other triangle), only slower (O(node count) for that ray). `trace_stats` counts
// rays that needed it. Tested in furnace-tests' traversal_parity.rs with stacks of 1 and 2 on the
// Cornell box and with a hand-built 100-level chain at the default size, against the CPU and
// brute force; with the sweep disabled those tests fail. The CPU twin (accel/src/traverse.rs)
// does the same.
// The Rust side can shrink the stack (`furnace_gpu::traverse::module_with_stack_size`) to test
// this path.
//
// Private helpers are prefixed `trv_`.

/// Result of `trace_closest`.
struct Hit {
    /// Ray parameter of the hit (`origin + t · dir`); the given t_max when there is no hit.
    t: f32,
    /// Barycentrics: the point is (1 − u − v)·v0 + u·v1 + v·v2.
    u: f32,
    v: f32,
    /// The caller's triangle id (`Triangle.id`); 0xffffffff when there is no hit.
    triangle: u32,
    /// Whether a triangle was hit.
    hit: bool,
    /// The instance that placed the triangle (an index of `instances`; 0 without instancing).
    instance: u32,
}

/// Counters of the traces run so far by this invocation (private memory: zero at the start of
/// each invocation, summed over its traces). Tests and profiling read them; the tracer does not,
/// and the integrator's rendering kernel composes none of their updates (they are in
/// TRACE_COUNTERS blocks: the counting kernel only).
struct TraceStats {
    /// Nodes whose 8 child boxes were tested (fallback sweeps included).
    nodes: u32,
    /// Ray-triangle tests.
    triangles: u32,
    /// Traces that overflowed the stack and ran the fallback sweep.
    fallbacks: u32,
    /// Deepest stack occupancy reached.
    max_depth: u32,
}

var<private> trace_stats: TraceStats;

/// Node groups the traversal stack holds; see "Traversal stack and its overflow" above. 16, not
/// the CPU's 32: a 32-entry stack takes more local and shared memory per invocation and slows
/// the megakernel (BENCHMARKS.md); the deepest stack seen in a real scene is 10 (10^7
/// triangles). The Rust side rewrites this line
/// to test the overflow path: keep its form.
const TRV_STACK_SIZE: u32 = 16u;

/// TRV_CULL_SLACK (`furnace_accel::CULL_SLACK`, 1 + 2^-12, generated before this module): boxes
/// are culled only beyond t_best · (1 + 2^-12), so that a triangle a few ULPs nearer than the
/// best hit, in a box whose computed entry is a few ULPs farther, is still found (near-ties at
/// shared edges).

/// Largest finite f32: an infinite t_max (bit pattern from a buffer) is clamped to it, since
/// some drivers treat infinities as undefined in arithmetic.
const TRV_F32_MAX: f32 = 3.40282347e38;

/// `accel::safe_recip`'s bounds: |x| < 2^-100 maps to ±2^100, so slab tests never see 0 · ∞.
const TRV_TINY: f32 = 7.888609e-31;
const TRV_HUGE: f32 = 1.2676506e30;

/// offset_ray_origin's constants TRV_ORIGIN, TRV_FLOAT_SCALE, TRV_INT_SCALE are generated before
/// this module from `furnace_accel::{ORIGIN, FLOAT_SCALE, INT_SCALE}`.

/// Whether x is finite, from its bits (robust where a driver assumes no NaN / infinity).
fn trv_is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn trv_is_finite3(v: vec3<f32>) -> bool {
    return trv_is_finite(v.x) && trv_is_finite(v.y) && trv_is_finite(v.z);
}

fn trv_safe_recip(x: f32) -> f32 {
    if abs(x) < TRV_TINY {
        return select(TRV_HUGE, -TRV_HUGE, (bitcast<u32>(x) & 0x80000000u) != 0u);
    }
    return 1.0 / x;
}

/// glam's `Vec3::cross`, same operation order.
fn trv_cross(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

/// glam's `Vec3::dot`, same operation order.
fn trv_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return (a.x * b.x) + (a.y * b.y) + (a.z * b.z);
}

/// `furnace_accel::offset_ray_origin_scaled` for one coordinate (`origin`, `float_scale`: the
/// constants times the scene's offset scale).
fn trv_offset_coord(p: f32, n: f32, origin: f32, float_scale: f32) -> f32 {
    if !trv_is_finite(p) || !trv_is_finite(n) {
        return p;
    }
    if abs(p) < origin {
        return p + float_scale * n;
    }
    // i32(f) truncates toward zero like Rust's `as i32` (|256 n| is small for a unit normal;
    // WGSL saturates out-of-range values as Rust does).
    let of_i = i32(TRV_INT_SCALE * n);
    let step = select(of_i, -of_i, p < 0.0);
    let moved = bitcast<f32>(bitcast<i32>(p) + step);
    return select(p, moved, trv_is_finite(moved));
}

/// Moves a surface point `p` along the geometric normal `n` (pointing to the side the new ray
/// leaves to) so that the ray does not hit the surface it leaves: Wächter & Binder 2019 with
/// the constants scaled by `scale` (`furnace_accel::offset_scale` of the scene's extent), twin
/// of `furnace_accel::offset_ray_origin_scaled` (bit-exact).
fn offset_ray_origin_scaled(p: vec3<f32>, n: vec3<f32>, scale: f32) -> vec3<f32> {
    let origin = TRV_ORIGIN * scale;
    let float_scale = TRV_FLOAT_SCALE * scale;
    return vec3<f32>(
        trv_offset_coord(p.x, n.x, origin, float_scale),
        trv_offset_coord(p.y, n.y, origin, float_scale),
        trv_offset_coord(p.z, n.z, origin, float_scale),
    );
}

/// `furnace_accel::offset_ray_origin`: [`offset_ray_origin_scaled`] at scale 1.
fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return offset_ray_origin_scaled(p, n, 1.0);
}

/// Result of the ray-triangle test; `t < 0` means no hit.
struct TrvTriHit {
    t: f32,
    u: f32,
    v: f32,
}

/// `furnace_accel::intersect_triangle`: two-sided Möller–Trumbore; hit when 0 < t < t_max and
/// (u, v) is in the closed triangle. Returns t = −1 for no hit.
fn trv_intersect_triangle(o: vec3<f32>, d: vec3<f32>, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, t_max: f32) -> TrvTriHit {
    let none = TrvTriHit(-1.0, 0.0, 0.0);
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = trv_cross(d, e2);
    let det = trv_dot(e1, p);
    if det == 0.0 || !trv_is_finite(det) {
        return none;
    }
    let inv_det = 1.0 / det;
    let s = o - v0;
    let u = trv_dot(s, p) * inv_det;
    if !(u >= 0.0 && u <= 1.0) {
        return none;
    }
    let q = trv_cross(s, e1);
    let v = trv_dot(d, q) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return none;
    }
    let t = trv_dot(e2, q) * inv_det;
    if !(t > 0.0 && t < t_max) {
        return none;
    }
    return TrvTriHit(t, u, v);
}

/// Per-ray constants of the node test.
struct TrvRay {
    o: vec3<f32>,
    inv_d: vec3<f32>,
    /// Direction component's sign bit set (−0.0 included), per axis.
    neg: vec3<bool>,
    /// obvhs's `ray_get_octant_inv4`: (7 − octant) in every byte.
    oct_inv4: u32,
}

fn trv_make_ray(o: vec3<f32>, d: vec3<f32>) -> TrvRay {
    let inv = vec3<f32>(trv_safe_recip(d.x), trv_safe_recip(d.y), trv_safe_recip(d.z));
    // Sign bits, not `d < 0`: a −0.0 component has the reciprocal −2^100, so it must enter
    // through the far plane like any negative one (with `d < 0` such a ray would miss every
    // box), as furnace-accel's NodeRay does.
    let neg = (bitcast<vec3<u32>>(d) >> vec3<u32>(31u)) == vec3<u32>(1u);
    let oct = select(0x04040404u, 0u, neg.x) | select(0x02020202u, 0u, neg.y) | select(0x01010101u, 0u, neg.z);
    return TrvRay(o, inv, neg, oct);
}

/// Byte `k` (0..7) of a pair of words.
fn trv_byte(w: vec2<u32>, k: u32) -> f32 {
    let word = select(w.x, w.y, k >= 4u);
    return f32((word >> (8u * (k & 3u))) & 0xffu);
}

/// The Ylitie et al. hit mask of `node` for children entered at t ∈ [0, t_cull]: bit 24 + (slot ^
/// octant) for an inner child, the unary triangle count shifted by the leaf's triangle offset
/// for a leaf child. `leaves_only` drops inner children (the fallback sweep).
fn trv_intersect_node(node: CwbvhNode, r: TrvRay, t_cull: f32, leaves_only: bool) -> u32 {
    // #if TRACE_COUNTERS
    trace_stats.nodes += 1u;
    // #endif
    let e = node.e_imask;
    let extent = vec3<f32>(
        bitcast<f32>((e & 0xffu) << 23u),
        bitcast<f32>(((e >> 8u) & 0xffu) << 23u),
        bitcast<f32>(((e >> 16u) & 0xffu) << 23u),
    );
    let scale = extent * r.inv_d;
    let offset = (vec3<f32>(node.p[0], node.p[1], node.p[2]) - r.o) * r.inv_d;
    // Entry / exit planes per axis: lo then hi for a positive direction, swapped for negative.
    let ex = select(node.child_min_x, node.child_max_x, r.neg.x);
    let lx = select(node.child_max_x, node.child_min_x, r.neg.x);
    let ey = select(node.child_min_y, node.child_max_y, r.neg.y);
    let ly = select(node.child_max_y, node.child_min_y, r.neg.y);
    let ez = select(node.child_min_z, node.child_max_z, r.neg.z);
    let lz = select(node.child_max_z, node.child_min_z, r.neg.z);
    var mask = 0u;
    for (var k = 0u; k < 8u; k++) {
        let word = select(node.child_meta.x, node.child_meta.y, k >= 4u);
        let cmeta = (word >> (8u * (k & 3u))) & 0xffu;
        if cmeta == 0u {
            continue; // empty slot: no bits to set (obvhs tests it anyway, to the same effect)
        }
        let is_inner = ((cmeta & (cmeta << 1u)) & 0x10u) != 0u;
        if leaves_only && is_inner {
            continue;
        }
        let tx0 = trv_byte(ex, k) * scale.x + offset.x;
        let ty0 = trv_byte(ey, k) * scale.y + offset.y;
        let tz0 = trv_byte(ez, k) * scale.z + offset.z;
        let tx1 = trv_byte(lx, k) * scale.x + offset.x;
        let ty1 = trv_byte(ly, k) * scale.y + offset.y;
        let tz1 = trv_byte(lz, k) * scale.z + offset.z;
        let enter = max(max(tx0, max(ty0, tz0)), 0.0);
        let leave = min(min(tx1, min(ty1, tz1)), t_cull);
        if enter <= leave {
            let bit_index = (cmeta ^ select(0u, r.oct_inv4 & 0xffu, is_inner)) & 0x1fu;
            let child_bits = (cmeta >> 5u) & 7u;
            mask |= child_bits << bit_index;
        }
    }
    return mask;
}

/// Traversal state shared by the closest-hit and any-hit loops.
struct TrvState {
    /// The nodes of the tree being traversed: its root and one past its last node (the sweep's
    /// range).
    node_first: u32,
    node_end: u32,
    /// The instance being traversed, and the one of the closest accepted hit.
    instance: u32,
    best_instance: u32,
    /// Closest accepted hit so far (t < 0: none).
    best: TrvTriHit,
    best_id: u32,
    /// Triangles are accepted only below this (closest: the best hit's t; any: t_max).
    t_tri: f32,
    /// Boxes entered beyond this are culled.
    t_cull: f32,
    /// Any-hit query: stop at the first accepted hit.
    any: bool,
    /// Set when an accepted hit ends an any-hit query.
    done: bool,
}

// #if SPLIT_TRIANGLES
/// Triangle slot `slot`: in the first binding up to its length, then in the second.
fn trv_triangle(slot: u32) -> Triangle {
    let low = arrayLength(&bvh_triangles);
    if slot < low {
        return bvh_triangles[slot];
    }
    return bvh_triangles_high[slot - low];
}
// #endif

/// Tests triangle slot `slot` and updates the state (accel's `visit` closures).
fn trv_leaf(st: ptr<function, TrvState>, o: vec3<f32>, d: vec3<f32>, slot: u32) {
    // #if TRACE_COUNTERS
    trace_stats.triangles += 1u;
    // #endif
    // #if SPLIT_TRIANGLES
    let tri = trv_triangle(slot);
    // #else
    let tri = bvh_triangles[slot];
    // #endif
    let h = trv_intersect_triangle(o, d, tri.v0, tri.v1, tri.v2, (*st).t_tri);
    // #if INSTANCES
    // The hit filter's shading (a sheet's normal) is the instance's.
    trv_instance = (*st).instance;
    // #endif
    if h.t > 0.0 && hit_filter(tri.id, h.u, h.v) {
        (*st).best = h;
        (*st).best_id = tri.id;
        (*st).best_instance = (*st).instance;
        if (*st).any {
            (*st).done = true;
        } else {
            (*st).t_tri = h.t;
            (*st).t_cull = h.t * TRV_CULL_SLACK;
        }
    }
}

/// Tests the triangles of hit mask `prims` (low 24 bits), highest bit first like the CPU.
fn trv_leaves(st: ptr<function, TrvState>, o: vec3<f32>, d: vec3<f32>, base: u32, prims_in: u32) {
    var prims = prims_in & 0x00ffffffu;
    while prims != 0u {
        let local = firstLeadingBit(prims);
        prims &= ~(1u << local);
        trv_leaf(st, o, d, base + local);
        if (*st).done {
            return;
        }
    }
}

/// The fallback after a stack overflow: every node's leaf children, tested with the current cull
/// distance (see the top of this file).
fn trv_sweep(st: ptr<function, TrvState>, r: TrvRay, o: vec3<f32>, d: vec3<f32>) {
    // #if TRACE_COUNTERS
    trace_stats.fallbacks += 1u;
    // #endif
    for (var i = (*st).node_first; i < (*st).node_end; i++) {
        let node = bvh_nodes[i];
        let hits = trv_intersect_node(node, r, (*st).t_cull, true);
        trv_leaves(st, o, d, node.primitive_base_idx, hits);
        if (*st).done {
            return;
        }
    }
}

/// accel's `traverse` (obvhs's `traverse!`): node groups (base, mask) on a stack, the children of
/// each group in octant order, a node's triangles tested right after the node.
fn trv_traverse(st: ptr<function, TrvState>, o: vec3<f32>, d: vec3<f32>) {
    if arrayLength(&bvh_nodes) == 0u {
        return;
    }
    let r = trv_make_ray(o, d);
    var stack: array<vec2<u32>, TRV_STACK_SIZE>;
    var depth = 0u;
    var dropped = false;
    var current = vec2<u32>((*st).node_first, 0x80000000u);
    loop {
        if (current.y & 0xff000000u) != 0u {
            let hits_imask = current.y;
            let child_index_offset = firstLeadingBit(hits_imask);
            current.y &= ~(1u << child_index_offset);
            if (current.y & 0xff000000u) != 0u {
                if depth == TRV_STACK_SIZE {
                    // Overflow: drop the bottom (shallowest) group; the sweep covers it.
                    for (var k = 1u; k < TRV_STACK_SIZE; k++) {
                        stack[k - 1u] = stack[k];
                    }
                    depth -= 1u;
                    dropped = true;
                }
                stack[depth] = current;
                depth += 1u;
                // #if TRACE_COUNTERS
                trace_stats.max_depth = max(trace_stats.max_depth, depth);
                // #endif
            }
            let slot_index = (child_index_offset - 24u) ^ (r.oct_inv4 & 0xffu);
            let relative_index = countOneBits(hits_imask & ~(0xffffffffu << slot_index));
            let node = bvh_nodes[current.x + relative_index];
            let hitmask = trv_intersect_node(node, r, (*st).t_cull, false);
            current = vec2<u32>(node.child_base_idx, (hitmask & 0xff000000u) | (node.e_imask >> 24u));
            trv_leaves(st, o, d, node.primitive_base_idx, hitmask);
            if (*st).done {
                return;
            }
        }
        if (current.y & 0xff000000u) == 0u {
            if depth == 0u {
                break;
            }
            depth -= 1u;
            current = stack[depth];
        }
    }
    if dropped {
        trv_sweep(st, r, o, d);
    }
}

// #if INSTANCES
// Two levels (furnace_accel::TwoLevel, built for the GPU with the world triangles as an
// instance of their own): a binary TLAS over the instances' boxes (`tlas_nodes`, a leaf names
// its instance), each instance's mesh a CWBVH in `bvh_nodes` (its nodes `root..node_end`),
// traversed with the ray carried into the instance by its inverse transform: t is unchanged
// (the direction is not renormalised), so the state's closest hit bounds every instance.

/// The instance of the hit being shaded, or of the candidate the hit filter judges.
var<private> trv_instance: u32;

/// TLAS nodes the stack holds; deeper trees finish with a sweep over the leaves (same hits).
const TRV_TLAS_STACK: u32 = 32u;

/// The ray's entry distance into a TLAS node's box, or −1 if it does not enter before `t_max`
/// (accel's `enter`: the exit widened by 2γ₃).
fn trv_tlas_enter(n: TlasNode, o: vec3<f32>, inv: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (n.min - o) * inv;
    let t1 = (n.max - o) * inv;
    let tmin = min(t0, t1);
    let tmax = max(t0, t1);
    let near = max(max(max(tmin.x, tmin.y), tmin.z), 0.0);
    let far = min(min(tmax.x, tmax.y), tmax.z) * (1.0 + 2.0 * TRV_GAMMA3);
    if near <= far && near < t_max {
        return near;
    }
    return -1.0;
}

/// γ₃ = 3ε/(1 − 3ε), ε = 2⁻²⁴.
const TRV_GAMMA3: f32 = 1.7881398e-7;

/// Traverses instance `i`'s mesh with the ray carried into it.
fn trv_visit_instance(st: ptr<function, TrvState>, i: u32, o: vec3<f32>, d: vec3<f32>) {
    let inst = instances[i];
    let o1 = vec4<f32>(o, 1.0);
    let d0 = vec4<f32>(d, 0.0);
    let oi = vec3<f32>(dot(inst.object_x, o1), dot(inst.object_y, o1), dot(inst.object_z, o1));
    let di = vec3<f32>(dot(inst.object_x, d0), dot(inst.object_y, d0), dot(inst.object_z, d0));
    if !trv_valid_ray(oi, di, (*st).t_tri) {
        return;
    }
    (*st).instance = i;
    (*st).node_first = inst.root;
    (*st).node_end = inst.node_end;
    trv_traverse(st, oi, di);
}

/// The TLAS loop: nearer child first, a stack of node indices (the far child), each leaf's
/// instance visited as it is reached.
fn trv_traverse_instances(st: ptr<function, TrvState>, o: vec3<f32>, d: vec3<f32>) {
    let inv = vec3<f32>(trv_safe_recip(d.x), trv_safe_recip(d.y), trv_safe_recip(d.z));
    var stack: array<u32, TRV_TLAS_STACK>;
    var depth = 0u;
    var dropped = false;
    var node = 0u;
    var running = true;
    while running {
        let n = tlas_nodes[node];
        var next = 0xffffffffu;
        if n.count > 0u {
            trv_visit_instance(st, n.first, o, d);
            if (*st).done {
                return;
            }
        } else {
            let a = n.first;
            let b = n.first + 1u;
            let ta = trv_tlas_enter(tlas_nodes[a], o, inv, (*st).t_cull);
            let tb = trv_tlas_enter(tlas_nodes[b], o, inv, (*st).t_cull);
            if ta >= 0.0 && tb >= 0.0 {
                var near = a;
                var far = b;
                if tb < ta {
                    near = b;
                    far = a;
                }
                if depth == TRV_TLAS_STACK {
                    // Overflow: drop the bottom entry; the sweep below covers it.
                    for (var k = 1u; k < TRV_TLAS_STACK; k++) {
                        stack[k - 1u] = stack[k];
                    }
                    depth -= 1u;
                    dropped = true;
                }
                stack[depth] = far;
                depth += 1u;
                next = near;
            } else if ta >= 0.0 {
                next = a;
            } else if tb >= 0.0 {
                next = b;
            }
        }
        // Pop the next subtree still entered before the closest hit.
        while next == 0xffffffffu {
            if depth == 0u {
                running = false;
                break;
            }
            depth -= 1u;
            if trv_tlas_enter(tlas_nodes[stack[depth]], o, inv, (*st).t_cull) >= 0.0 {
                next = stack[depth];
            }
        }
        node = next;
    }
    if dropped {
        let count = arrayLength(&tlas_nodes);
        for (var k = 0u; k < count; k++) {
            let n = tlas_nodes[k];
            if n.count > 0u && trv_tlas_enter(n, o, inv, (*st).t_cull) >= 0.0 {
                trv_visit_instance(st, n.first, o, d);
                if (*st).done {
                    return;
                }
            }
        }
    }
}
// #endif

fn trv_valid_ray(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> bool {
    return trv_is_finite3(o) && trv_is_finite3(d) && any(d != vec3<f32>(0.0)) && t_max > 0.0;
}

/// One query of either kind, for a caller that traces both through one call site (the driver
/// inlines a copy of the traversal per call site): `any` false is [`trace_closest`]; `any`
/// true is [`trace_any`], the result's `hit` telling whether the ray is blocked (its t, u, v
/// and triangle are then those of the first blocking hit found, not the closest).
fn trace_query(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, any: bool) -> Hit {
    var miss = Hit(t_max, 0.0, 0.0, 0xffffffffu, false, 0u);
    if !trv_valid_ray(origin, dir, t_max) {
        return miss;
    }
    let tm = min(t_max, TRV_F32_MAX);
    var st = TrvState(0u, arrayLength(&bvh_nodes), 0u, 0u, TrvTriHit(-1.0, 0.0, 0.0), 0xffffffffu, tm,
        min(tm * TRV_CULL_SLACK, TRV_F32_MAX), any, false);
    // #if INSTANCES
    trv_traverse_instances(&st, origin, dir);
    // #else
    trv_traverse(&st, origin, dir);
    // #endif
    if st.best.t > 0.0 {
        // #if INSTANCES
        // What the shading of this hit reads (scene.wgsl's placing functions).
        trv_instance = st.best_instance;
        // #endif
        return Hit(st.best.t, st.best.u, st.best.v, st.best_id, true, st.best_instance);
    }
    return miss;
}

/// The closest triangle hit by `origin + t · dir`, 0 < t < t_max, that `hit_filter` accepts:
/// twin of `furnace_accel::Bvh::closest_hit_masked`. `dir` need not be normalised; a
/// non-finite origin or direction, a zero direction or t_max ≤ 0 hit nothing.
fn trace_closest(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> Hit {
    return trace_query(origin, dir, t_max, false);
}

/// Whether a triangle that `hit_filter` accepts intersects `origin + t · dir` at 0 < t < t_max
/// (a shadow ray); stops at the first such hit. Twin of `furnace_accel::Bvh::occluded_masked`.
fn trace_any(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    return trace_query(origin, dir, t_max, true).hit;
}
