//! The WGSL sources, twins of the Rust code of the CPU crates.
//!
//! WGSL has no `#include`: a shader is the concatenation of the modules it needs, in dependency
//! order, done by [`compose`]. Each module documents what it requires before it.

/// `furnace-sampling`'s samplers (random, Hammersley, CMJ, PMJ02, Owen-Sobol) and warps,
/// bit-identical to the Rust (all `u32` arithmetic, 0.32 fixed point).
pub const SAMPLING: &str = include_str!("wgsl/sampling.wgsl");

/// `furnace-brdf`'s BSDFs: Lambert, GGX (NDF / VNDF / spherical-cap sampling, separable and
/// height-correlated Smith masking, Schlick Fresnel), Turquin compensation, glTF
/// metallic-roughness. Needs [`SAMPLING`] (warps).
pub const BRDF: &str = include_str!("wgsl/brdf.wgsl");

/// `furnace-scene`'s per-hit code over the scene buffers of [`crate::scene`]: attribute
/// interpolation (octahedral normals, UVs, tangents), bilinear RGBA8 texture lookups with wrap
/// modes, sRGB decode and KHR_texture_transform, `Material::evaluate`, furnace-cpu's
/// `surface_point` (normal map, double-sided orientation) and alpha test. Needs the
/// declarations of [`crate::scene::bindings`].
pub const SCENE: &str = include_str!("wgsl/scene.wgsl");

/// CWBVH traversal of `furnace-accel`'s GPU buffers: closest hit and any hit (shadow rays).
pub const TRAVERSE: &str = include_str!("wgsl/traverse.wgsl");

/// The integrator's per-path pieces with Rust twins: the camera ray (`furnace-scene`'s
/// `Camera::generate_ray`), the shading frame (`furnace_brdf::Frame`) and Russian roulette's
/// survival probability (`furnace_render::russian_roulette_survival`). Needs the `FRAME_*`
/// constants and a `params: FrameParams` (see [`crate::integrator`]).
pub const PATH: &str = include_str!("wgsl/path.wgsl");

/// Concatenates WGSL modules (in the order given) into one shader source.
pub fn compose(parts: &[&str]) -> String {
    let mut s = String::with_capacity(parts.iter().map(|p| p.len() + 1).sum());
    for p in parts {
        s.push_str(p);
        s.push('\n');
    }
    s
}
