//! Rust side of the WGSL BSDFs ([`crate::wgsl::BRDF`]): the per-hit material record
//! [`BsdfParams`], the option flags and lobe codes, and the Turquin table a shader receives.
//!
//! The WGSL module is a twin of `furnace-brdf`'s [`MetallicRoughness`] (Lambert + one merged GGX
//! lobe, all [`SpecularOptions`]); `tests/brdf_parity.rs` runs both on the same inputs. Its API:
//!
//! ```wgsl
//! fn bsdf_eval(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32>    // Bsdf::eval
//! fn bsdf_pdf(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32           // Bsdf::pdf
//! fn bsdf_sample(m: BsdfParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample
//! fn bsdf_params(base_color, metallic, roughness, specular_factor, specular_color, flags)
//! ```
//!
//! `bsdf_sample(m, wo, u_lobe, u)` is `Bsdf::sample(wo, uc, u)`: the same three numbers in the
//! same roles, so GPU and CPU paths consume the same sampler dimensions. The shader that
//! includes the module declares `var<storage, read> turquin_table: array<f32>;` bound to
//! [`turquin_table`].

use bytemuck::{Pod, Zeroable};
use furnace_brdf::turquin::{E_SS_HEIGHT_CORRELATED, E_SS_SEPARABLE, TABLE_SIZE};
use furnace_brdf::{
    Lobe, Masking, MetallicRoughness, MetallicRoughnessParams, SpecularOptions, SpecularSampling,
};

/// `BsdfParams.flags` bit 0: height-correlated masking (clear: separable).
pub const FLAG_HEIGHT_CORRELATED: u32 = 1;
/// `BsdfParams.flags` bits 1–2 hold the sampling method, shifted by this.
pub const SAMPLING_SHIFT: u32 = 1;
/// The sampling method's mask (after the shift).
pub const SAMPLING_MASK: u32 = 3;
/// Sampling method code of [`SpecularSampling::Ndf`].
pub const SAMPLING_NDF: u32 = 0;
/// Sampling method code of [`SpecularSampling::Vndf`].
pub const SAMPLING_VNDF: u32 = 1;
/// Sampling method code of [`SpecularSampling::SphericalCaps`].
pub const SAMPLING_CAPS: u32 = 2;
/// `BsdfParams.flags` bit 3: Turquin energy compensation.
pub const FLAG_COMPENSATION: u32 = 8;

/// `BsdfSample.lobe` when no direction was sampled (the Rust `None`).
pub const LOBE_NONE: u32 = 0;
/// `BsdfSample.lobe` of [`Lobe::Diffuse`].
pub const LOBE_DIFFUSE: u32 = 1;
/// `BsdfSample.lobe` of [`Lobe::Specular`].
pub const LOBE_SPECULAR: u32 = 2;

/// The number of `f32` in [`turquin_table`]: two tables of `TABLE_SIZE²`.
pub const TURQUIN_TABLE_LEN: usize = 2 * TABLE_SIZE * TABLE_SIZE;

/// The WGSL `flags` of a [`SpecularOptions`].
pub fn options_flags(options: SpecularOptions) -> u32 {
    let masking = match options.masking {
        Masking::Separable => 0,
        Masking::HeightCorrelated => FLAG_HEIGHT_CORRELATED,
    };
    let sampling = match options.sampling {
        SpecularSampling::Ndf => SAMPLING_NDF,
        SpecularSampling::Vndf => SAMPLING_VNDF,
        SpecularSampling::SphericalCaps => SAMPLING_CAPS,
    };
    let compensation = if options.compensation { FLAG_COMPENSATION } else { 0 };
    masking | (sampling << SAMPLING_SHIFT) | compensation
}

/// The WGSL `BsdfSample.lobe` code of a Rust sample's lobe (`None`: no sample).
pub fn lobe_code(lobe: Option<Lobe>) -> u32 {
    match lobe {
        None => LOBE_NONE,
        Some(Lobe::Diffuse) => LOBE_DIFFUSE,
        Some(Lobe::Specular) => LOBE_SPECULAR,
    }
}

/// The per-hit material record of the WGSL BSDF: a [`MetallicRoughness`] after its constructor
/// (clamping, α = roughness², F0/F90 of the merged lobe), 64 bytes. Twin of WGSL
/// `struct BsdfParams` (layout checked by `tests/brdf_parity.rs`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct BsdfParams {
    /// Lambert albedo `baseColor·(1 − metallic)` (before the Fresnel weighting).
    pub diffuse: [f32; 3],
    /// GGX α, clamped to `[ALPHA_MIN, 1]`.
    pub alpha: f32,
    /// Specular F0 of the merged lobe.
    pub f0: [f32; 3],
    /// Specular F90 (all channels alike for this material).
    pub f90: f32,
    /// `min(0.04·specularColor, 1)`: the dielectric F0 before `specular_factor`.
    pub f0_dielectric: [f32; 3],
    /// KHR_materials_specular `specularFactor`, clamped to `[0, 1]`.
    pub specular_factor: f32,
    /// The [`SpecularOptions`] ([`options_flags`]).
    pub flags: u32,
    /// Padding to WGSL's 16-byte struct alignment.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

const _: () = assert!(size_of::<BsdfParams>() == 64);

impl BsdfParams {
    /// The record of `MetallicRoughness::new(params, options)`: the lobes' fields are read from
    /// the Rust material itself; the two private ones (`specularFactor`, the dielectric F0) are
    /// formed as its constructor forms them (and `eval` parity tests that they agree).
    pub fn new(params: MetallicRoughnessParams, options: SpecularOptions) -> Self {
        let bsdf = MetallicRoughness::new(params, options);
        let spec = &bsdf.specular;
        // MetallicRoughness::new: sF sanitised to [0, 1] (NaN → 1), specularColor clamped to
        // [0, f32::MAX] (NaN → 0), F0 of the dielectric = min(0.04·specularColor, 1).
        let sf = params.specular_factor;
        let sf = if sf.is_nan() { 1.0 } else { sf.clamp(0.0, 1.0) };
        let clamp = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, f32::MAX) };
        let sc = params.specular_color;
        let f0_dielectric =
            (0.04 * glam::Vec3::new(clamp(sc.x), clamp(sc.y), clamp(sc.z))).min(glam::Vec3::ONE);
        Self {
            diffuse: bsdf.diffuse.albedo.to_array(),
            alpha: spec.ggx.alpha(),
            f0: spec.f0.to_array(),
            f90: spec.f90.x,
            f0_dielectric: f0_dielectric.to_array(),
            specular_factor: sf,
            flags: options_flags(spec.options),
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        }
    }

    /// The record the CPU integrator's material would be: `MetallicRoughness` of the
    /// material's evaluated parameters, exactly as `furnace-cpu` builds it per hit.
    pub fn from_material(sample: &furnace_scene::MaterialSample, options: SpecularOptions) -> Self {
        Self::new(
            MetallicRoughnessParams {
                base_color: sample.base_color,
                metallic: sample.metallic,
                roughness: sample.roughness,
                specular_factor: sample.specular_factor,
                specular_color: sample.specular_color,
            },
            options,
        )
    }
}

/// The Turquin `E_ss(μ, α)` tables as the WGSL `turquin_table: array<f32>` holds them:
/// `furnace_brdf::turquin::E_SS_SEPARABLE` then `E_SS_HEIGHT_CORRELATED`, each row-major
/// `[α row j][μ column i]`, so entry `(m·64 + j)·64 + i` with `m` = 0 separable, 1
/// height-correlated ([`TURQUIN_TABLE_LEN`] floats).
pub fn turquin_table() -> Vec<f32> {
    let mut v = Vec::with_capacity(TURQUIN_TABLE_LEN);
    for table in [&E_SS_SEPARABLE, &E_SS_HEIGHT_CORRELATED] {
        for row in table.iter() {
            v.extend_from_slice(row);
        }
    }
    v
}
