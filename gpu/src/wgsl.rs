//! The WGSL sources, twins of the Rust code of the CPU crates.
//!
//! WGSL has no `#include`: a shader is the concatenation of the modules it needs, in dependency
//! order, done by [`compose`]. Each module documents what it requires before it.
//!
//! Nor has it conditional compilation: [`select`] keeps or drops the lines between
//! `// #if NAME` and `// #endif` (with an optional `// #else`), so that a shader holds no code,
//! variable or binding of a feature its scene lacks — not even behind a `false` constant, which
//! a driver is free to compile and keep registers for.

/// `furnace-sampling`'s samplers (random, Hammersley, CMJ, PMJ02, Owen-Sobol) and warps,
/// bit-identical to the Rust (all `u32` arithmetic, 0.32 fixed point).
pub const SAMPLING: &str = include_str!("wgsl/sampling.wgsl");

/// `furnace-brdf`'s BSDFs: Lambert, GGX (NDF / VNDF / spherical-cap sampling, separable and
/// height-correlated Smith masking, Schlick Fresnel), Turquin compensation, glTF
/// metallic-roughness. Needs [`SAMPLING`] (warps) and [`crate::brdf::declarations`]. Compose
/// it through [`select`]: `IRIDESCENCE` keeps the thin film, `ANISOTROPY` the stretched GGX
/// (`GgxAlpha` is then `(αx, αy)`, else `α`).
///
/// One WGSL file per Rust file of `furnace-brdf` (`brdf.wgsl` is the twin of its `lib.rs`),
/// concatenated in dependency order; the list lives beside the GPU record, in
/// [`crate::brdf::WGSL`], so that a lobe's Rust side on the GPU is one file.
pub const BRDF: &str = crate::brdf::WGSL;

/// `furnace-brdf`'s dielectric module: exact Fresnel, smooth / rough / thin-walled interfaces
/// and the glTF transmissive mixture. Needs [`BRDF`].
pub const DIELECTRIC: &str = include_str!("wgsl/dielectric.wgsl");

/// `furnace-brdf`'s diffuse transmission lobe (KHR_materials_diffuse_transmission). Needs
/// [`BRDF`]; composed for scenes with diffuse transmission only.
pub const DIFFUSE_TRANSMISSION: &str = include_str!("wgsl/diffuse_transmission.wgsl");

/// `furnace-brdf`'s spectrum module (KHR_materials_dispersion): the path's wavelength and the
/// index at it. Needs [`DIELECTRIC`] and the tables of `furnace_brdf::spectrum::wgsl`;
/// composed for scenes with a dispersive material only.
pub const SPECTRUM: &str = include_str!("wgsl/spectrum.wgsl");

/// `furnace-scene`'s per-hit code over the scene buffers of [`crate::scene`]: attribute
/// interpolation (octahedral normals, UVs, tangents), bilinear RGBA8 texture lookups with wrap
/// modes, sRGB decode and KHR_texture_transform, `Material::evaluate`, furnace-cpu's
/// `surface_point` (normal map, double-sided orientation) and alpha test. Needs the
/// declarations of [`crate::scene::bindings`]. Compose it through [`select`]: `UV_SETS` and
/// `VERTEX_COLORS` keep the reads of UV sets beyond UV0 and of vertex colours, `INSTANCES` the
/// placing of a hit by its instance (which needs the two-level traversal's bindings).
pub const SCENE: &str = include_str!("wgsl/scene.wgsl");

/// `furnace-scene`'s light BVH (`LightBounds::importance`, `LightBvh::sample` and `pmf`) over
/// the nodes in the `emitters` buffer ([`crate::integrator::light_bvh_words`]). Needs only
/// that buffer and the constants of [`crate::integrator::light_bvh_consts_wgsl`].
pub const LIGHT_BVH: &str = include_str!("wgsl/light_bvh.wgsl");

/// `furnace-scene`'s environment maps (the texel-centred lat-long lookup, the rotation,
/// `EnvironmentSampler::sample` and `pdf` over `furnace_sampling::Distribution2D`'s CDFs) over
/// the `environment` buffer ([`crate::integrator::environment_words`]); its sampling half is
/// in a `// #if SAMPLES_ENVIRONMENT` block ([`select`]).
pub const ENVIRONMENT: &str = include_str!("wgsl/environment.wgsl");

/// CWBVH traversal of `furnace-accel`'s GPU buffers: closest hit and any hit (shadow rays).
/// Compose it through [`select`]: `INSTANCES` keeps the two-level traversal (TLAS and instance
/// buffers), else the one-level one ([`crate::traverse::one_level`]); `TRACE_COUNTERS` keeps the
/// counters' updates.
pub const TRAVERSE: &str = include_str!("wgsl/traverse.wgsl");

/// The integrator's per-path pieces with Rust twins: the camera ray (`furnace-scene`'s
/// `Camera::generate_ray`), the shading frame (`furnace_brdf::Frame`) and Russian roulette's
/// survival probability (`furnace_render::russian_roulette_survival`). Needs the `FRAME_*`
/// constants and a `params: FrameParams` (see [`crate::integrator`]). Compose it through
/// [`select`]: `ANISOTROPY` keeps the frame along a tangent (`Frame::with_tangent`).
pub const PATH: &str = include_str!("wgsl/path.wgsl");

/// The BSDF at a hit (`HitBsdf`, `hit_bsdf`, `hit_eval`, `hit_pdf`): the glTF material's
/// layering, the twin of `furnace_brdf::HitBsdf` (`brdf/src/layered.rs`). Needs [`BRDF`], and
/// [`DIELECTRIC`] where its `// #if TRANSMISSION` blocks are kept.
pub const MATERIAL: &str = include_str!("wgsl/layered.wgsl");

/// The layers above the glTF material (KHR_materials_clearcoat, KHR_materials_sheen): the
/// twins of `furnace-brdf`'s `clearcoat.rs`, `sheen.rs` and the layering of `layered.rs`.
/// Composed before [`MATERIAL`] for scenes with a coat or a sheen, through [`select`]
/// (`CLEARCOAT`, `SHEEN`, `VERTEX_ATTRIBUTES`); reads `scene_layers` and the sheen table at the
/// end of `turquin_table`.
pub const LAYERS: &str = include_str!("wgsl/layers.wgsl");

/// Concatenates WGSL modules (in the order given) into one shader source.
pub fn compose(parts: &[&str]) -> String {
    let mut s = String::with_capacity(parts.iter().map(|p| p.len() + 1).sum());
    for p in parts {
        s.push_str(p);
        s.push('\n');
    }
    s
}

/// `source` with its `// #if NAME` (or `// #if !NAME`) … `// #else` … `// #endif` blocks
/// resolved by `enabled(NAME)` (blocks nest; the directive lines themselves are dropped). The directives must each stand on
/// their own line, indentation allowed.
///
/// # Panics
/// On an unbalanced `#else` / `#endif` or an unterminated `#if`: the shaders are this crate's
/// own sources, so that is a bug here, caught by any test that composes the shader.
pub fn select(source: &str, enabled: impl Fn(&str) -> bool) -> String {
    let mut out = String::with_capacity(source.len());
    // Per open block: (whether its lines are kept, whether the enclosing block is kept).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let live = |stack: &[(bool, bool)]| stack.last().is_none_or(|&(keep, _)| keep);
    for (n, line) in source.lines().enumerate() {
        let directive = line.trim_start().strip_prefix("// #");
        match directive.map(|d| d.split_whitespace().collect::<Vec<_>>()).as_deref() {
            Some(["if", name]) => {
                let outer = live(&stack);
                let on = match name.strip_prefix('!') {
                    Some(n) => !enabled(n),
                    None => enabled(name),
                };
                stack.push((outer && on, outer));
            }
            Some(["else"]) => {
                let (keep, outer) =
                    stack.pop().unwrap_or_else(|| panic!("line {}: #else without #if", n + 1));
                stack.push((outer && !keep, outer));
            }
            Some(["endif"]) => {
                stack.pop().unwrap_or_else(|| panic!("line {}: #endif without #if", n + 1));
            }
            _ => {
                if live(&stack) {
                    out.push_str(line);
                    out.push('\n');
                }
            }
        }
    }
    assert!(stack.is_empty(), "unterminated #if");
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn select_keeps_enabled_blocks_only() {
        let src = "a\n// #if X\nx\n  // #if Y\n  y\n  // #else\n  not y\n  // #endif\n// #else\nnot x\n// #endif\nb\n";
        assert_eq!(super::select(src, |n| n == "X"), "a\nx\n  not y\nb\n");
        assert_eq!(super::select(src, |n| n == "Y"), "a\nnot x\nb\n");
        assert_eq!(super::select(src, |_| true), "a\nx\n  y\nb\n");
        assert_eq!(super::select("// #if !X\nno x\n// #endif\n", |_| false), "no x\n");
    }
}
