// furnace-gpu: the light BVH, twin of furnace_scene::LightBvh (sample, pmf) and
// LightBounds::importance, the same f32 arithmetic in the same order.
//
// Requires: `emitters: array<vec4<u32>>` holding the nodes from element `base` on, three
// vec4 each (furnace_gpu::integrator::light_bvh_words: lo.xyz, phi | hi.xyz, cos_theta_o |
// axis.xyz, child; 16-byte loads), and LIGHT_BVH_LEAF (generated from furnace_scene::LIGHT_BVH_LEAF). Nothing
// else: it composes alone (the parity tests run it so).

struct LightBvhBounds {
    lo: vec3<f32>,
    phi: f32,
    hi: vec3<f32>,
    cos_theta_o: f32,
    axis: vec3<f32>,
    child: u32,
}

fn light_bvh_node(base: u32, index: u32) -> LightBvhBounds {
    let k = base + (LIGHT_BVH_NODE_WORDS / 4u) * index;
    let a = bitcast<vec4<f32>>(emitters[k]);
    let b = bitcast<vec4<f32>>(emitters[k + 1u]);
    let c = emitters[k + 2u];
    return LightBvhBounds(a.xyz, a.w, b.xyz, b.w, bitcast<vec3<f32>>(c.xyz), c.w);
}

// Vec3::dot: (x·x' + y·y') + z·z' (scene.wgsl's scene_dot, repeated so the module stands alone).
fn light_bvh_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn light_bvh_safe_sqrt(x: f32) -> f32 {
    return sqrt(max(x, 0.0));
}

// pbrt's cosSubClamped: cos(max(0, a − b)).
fn light_bvh_cos_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        return 1.0;
    }
    return cos_a * cos_b + sin_a * sin_b;
}

// pbrt's sinSubClamped: sin(max(0, a − b)).
fn light_bvh_sin_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        return 0.0;
    }
    return sin_a * cos_b - cos_a * sin_b;
}

// LightBounds::importance.
fn light_bvh_importance(b: LightBvhBounds, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let centre = 0.5 * (b.lo + b.hi);
    let half = 0.5 * (b.hi - b.lo);
    let r2 = light_bvh_dot(half, half);
    let to_p = p - centre;
    let dist2 = light_bvh_dot(to_p, to_p);
    if !(dist2 > r2) {
        if r2 > 0.0 {
            return b.phi / r2;
        }
        return 0.0;
    }
    let inv_dist2 = 1.0 / dist2;
    let wi = to_p * (1.0 / sqrt(dist2));
    let sin2_b = r2 * inv_dist2;
    let sin_b = sqrt(sin2_b);
    let cos_b = light_bvh_safe_sqrt(1.0 - sin2_b);
    let cos_w = light_bvh_dot(b.axis, wi);
    let sin_w = light_bvh_safe_sqrt(1.0 - cos_w * cos_w);
    var sin_o = 0.0;
    if b.cos_theta_o < 1.0 {
        sin_o = light_bvh_safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o);
    }
    let cos_x = light_bvh_cos_sub(sin_w, cos_w, sin_o, b.cos_theta_o);
    let sin_x = light_bvh_sin_sub(sin_w, cos_w, sin_o, b.cos_theta_o);
    let cos_p = light_bvh_cos_sub(sin_x, cos_x, sin_b, cos_b);
    if !(cos_p > 0.0) {
        return 0.0;
    }
    var importance = b.phi * cos_p * inv_dist2;
    if any(n != vec3<f32>(0.0)) {
        let cos_i = -light_bvh_dot(wi, n);
        let sin_i = light_bvh_safe_sqrt(1.0 - cos_i * cos_i);
        let cos_pi = light_bvh_cos_sub(sin_i, cos_i, sin_b, cos_b);
        if !(cos_pi > 0.0) {
            return 0.0;
        }
        importance *= cos_pi;
    }
    return importance;
}

// LightBvh::children: the importances of interior node `index`'s children (the first follows
// it, the second is `second`) and their sum.
fn light_bvh_children(base: u32, index: u32, second: u32, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let c0 = light_bvh_importance(light_bvh_node(base, index + 1u), p, n);
    let c1 = light_bvh_importance(light_bvh_node(base, second), p, n);
    return vec3<f32>(c0, c1, c0 + c1);
}

// LightBvh::sample: the item and its probability; pmf 0 when no item can light p.
struct LightBvhChoice {
    item: u32,
    pmf: f32,
}

fn light_bvh_sample(base: u32, p: vec3<f32>, n: vec3<f32>, u_in: f32) -> LightBvhChoice {
    let one_minus_epsilon = bitcast<f32>(0x3f7fffffu);
    var u = u_in;
    var index = 0u;
    var pmf = 1.0;
    loop {
        let node = light_bvh_node(base, index);
        if (node.child & LIGHT_BVH_LEAF) != 0u {
            if index > 0u || light_bvh_importance(node, p, n) > 0.0 {
                return LightBvhChoice(node.child & ~LIGHT_BVH_LEAF, pmf);
            }
            return LightBvhChoice(0u, 0.0);
        }
        let level_children = light_bvh_children(base, index, node.child, p, n);
        let second = node.child;
        let c0 = level_children.x;
        let c1 = level_children.y;
        let sum = level_children.z;
        if !(sum > 0.0) {
            return LightBvhChoice(0u, 0.0);
        }
        let p0 = c0 / sum;
        if u < p0 {
            u = min(u / p0, one_minus_epsilon);
            pmf *= c0 / sum;
            index += 1u;
        } else {
            u = min((u - p0) / (1.0 - p0), one_minus_epsilon);
            pmf *= c1 / sum;
            index = second;
        }
    }
    return LightBvhChoice(0u, 0.0);
}

// LightBvh::pmf of the item whose path from the root is `trail` (low word: levels 0–31).
fn light_bvh_pmf(base: u32, trail: vec2<u32>, p: vec3<f32>, n: vec3<f32>) -> f32 {
    var index = 0u;
    var pmf = 1.0;
    var level = 0u;
    loop {
        let node = light_bvh_node(base, index);
        if (node.child & LIGHT_BVH_LEAF) != 0u {
            if index > 0u || light_bvh_importance(node, p, n) > 0.0 {
                return pmf;
            }
            return 0.0;
        }
        let level_children = light_bvh_children(base, index, node.child, p, n);
        let second = node.child;
        let c0 = level_children.x;
        let c1 = level_children.y;
        let sum = level_children.z;
        if !(sum > 0.0) {
            return 0.0;
        }
        var bit: u32;
        if level < 32u {
            bit = (trail.x >> level) & 1u;
        } else {
            bit = (trail.y >> (level - 32u)) & 1u;
        }
        if bit == 0u {
            pmf *= c0 / sum;
            index += 1u;
        } else {
            pmf *= c1 / sum;
            index = second;
        }
        level += 1u;
    }
    return 0.0;
}
