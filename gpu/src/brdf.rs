//! Rust side of the WGSL BSDFs ([`crate::wgsl::BRDF`]): the per-hit material record
//! [`BsdfParams`], the option flags and lobe codes, and the Turquin table a shader receives.
//!
//! The WGSL module is a twin of `furnace-brdf`'s [`MetallicRoughness`] (Lambert + one merged GGX
//! lobe, all [`SpecularOptions`]), one `.wgsl` file per Rust file of `furnace-brdf`;
//! `tests/brdf_parity.rs` runs both on the same inputs. Its API:
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

use crate::shared::{WgslType, wgsl_struct};
use bytemuck::Zeroable;
use furnace_brdf::iridescence::ThinFilm;
use furnace_brdf::turquin::{E_SS_HEIGHT_CORRELATED, E_SS_SEPARABLE, TABLE_SIZE};
use furnace_brdf::{
    Lobe, Masking, MetallicRoughness, MetallicRoughnessParams, SpecularOptions, SpecularSampling,
};

/// The WGSL of `furnace-brdf` ([`crate::wgsl::BRDF`]): one file per Rust file of the crate
/// (`brdf.wgsl` is the twin of its `lib.rs`), concatenated in dependency order. A new lobe adds
/// its file here.
pub const WGSL: &str = concat!(
    include_str!("wgsl/brdf.wgsl"),
    include_str!("wgsl/fresnel.wgsl"),
    include_str!("wgsl/iridescence.wgsl"),
    include_str!("wgsl/ggx.wgsl"),
    include_str!("wgsl/turquin.wgsl"),
    include_str!("wgsl/specular.wgsl"),
    include_str!("wgsl/lambert.wgsl"),
    include_str!("wgsl/metallic_roughness.wgsl"),
);

crate::wgsl_consts! {
    /// The WGSL `const` declarations of the flag and lobe codes below (`BSDF_` + the Rust
    /// name), composed by [`declarations`].
    fn consts_wgsl prefix "BSDF_";
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
    /// A sample of the clear coat.
    pub const LOBE_CLEARCOAT: u32 = 3;
    /// A sample of the sheen.
    pub const LOBE_SHEEN: u32 = 4;
}

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
        Some(Lobe::Clearcoat) => LOBE_CLEARCOAT,
        Some(Lobe::Sheen) => LOBE_SHEEN,
    }
}

crate::gpu_struct! {
    /// The per-hit material record of the WGSL BSDF: a [`MetallicRoughness`] after its
    /// constructor (clamping, α = roughness², F0/F90 of the merged lobe, the thin film, the
    /// anisotropic α), 96 bytes. Its WGSL declaration is generated ([`declarations`]). A kernel without
    /// iridescence never reads the film's fields (its code is not composed), so the compiler
    /// drops them.
    pub struct BsdfParams {
        /// Lambert albedo `baseColor·(1 − metallic)` (before the Fresnel weighting).
        pub diffuse: [f32; 3] => WgslType::VEC3_F32,
        /// GGX α, clamped to `[ALPHA_MIN, 1]`.
        pub alpha: f32 => WgslType::F32,
        /// Specular F0 of the merged lobe.
        pub f0: [f32; 3] => WgslType::VEC3_F32,
        /// Specular F90 (all channels alike for this material).
        pub f90: f32 => WgslType::F32,
        /// `min(0.04·specularColor, 1)`: the dielectric F0 before `specular_factor`.
        pub f0_dielectric: [f32; 3] => WgslType::VEC3_F32,
        /// KHR_materials_specular `specularFactor`, clamped to `[0, 1]`.
        pub specular_factor: f32 => WgslType::F32,
        /// The [`SpecularOptions`] ([`options_flags`]).
        pub flags: u32 => WgslType::U32,
        /// KHR_materials_iridescence: the film's weight `i` (0: no film, the fields below
        /// unused).
        pub film_factor: f32 => WgslType::F32,
        /// The film's index of refraction.
        pub film_ior: f32 => WgslType::F32,
        /// The film's thickness (nm).
        pub film_thickness: f32 => WgslType::F32,
        /// The metal's base F0 under the film, `baseColor`.
        pub film_f0_metal: [f32; 3] => WgslType::VEC3_F32,
        /// `metallic`, mixing the film over the dielectric and over the metal.
        pub film_metallic: f32 => WgslType::F32,
        /// The compensation's F0 under the film: the mixed Fresnel at `ωo·ωm = 1`.
        pub film_f0: [f32; 3] => WgslType::VEC3_F32,
        /// GGX α along the frame's y axis: `alpha` unless the lobe is anisotropic
        /// (KHR_materials_anisotropy, `alpha` then along x, the anisotropy direction). Read only
        /// by kernels composed with `ANISOTROPY`.
        pub alpha_y: f32 => WgslType::F32,
    }
}

/// The WGSL declarations [`crate::wgsl::BRDF`] needs before it, generated: the `BSDF_FLAG_*`,
/// `BSDF_SAMPLING_*` and `BSDF_LOBE_*` constants, `BSDF_LUMINANCE` ([`luminance_const`]) and
/// `struct BsdfParams`.
pub fn declarations() -> String {
    consts_wgsl() + &luminance_const("BSDF_LUMINANCE") + &wgsl_struct::<BsdfParams>(false)
}

/// The WGSL line `const NAME: vec3<f32> = vec3<f32>(…);` of the Rec. 709 luminance weights
/// [`furnace_sampling::LUMINANCE`], for every shader module that weighs colours by luminance.
/// The literals are Rust's shortest round-trip spelling of each `f32`, so WGSL reads the same
/// values.
pub fn luminance_const(name: &str) -> String {
    let [r, g, b] = furnace_sampling::LUMINANCE;
    format!("const {name}: vec3<f32> = vec3<f32>({r:?}, {g:?}, {b:?});\n")
}

const _: () = assert!(size_of::<BsdfParams>() == 96);

impl BsdfParams {
    /// The record of `MetallicRoughness::new(params, options)`, every field read from the Rust
    /// material itself.
    pub fn new(params: MetallicRoughnessParams, options: SpecularOptions) -> Self {
        Self::of(&MetallicRoughness::new(params, options))
    }

    /// The record of a Rust material, every field read from it.
    pub fn of(bsdf: &MetallicRoughness) -> Self {
        let spec = &bsdf.specular;
        let mut r = Self {
            diffuse: bsdf.diffuse.albedo.to_array(),
            alpha: spec.ggx.alphas().0,
            alpha_y: spec.ggx.alphas().1,
            f0: spec.f0.to_array(),
            f90: spec.f90.x,
            f0_dielectric: bsdf.f0_dielectric().to_array(),
            specular_factor: bsdf.specular_factor(),
            flags: options_flags(spec.options),
            ..Self::zeroed()
        };
        if let Some((film, f0)) = &spec.iridescence {
            r.film_factor = film.factor;
            r.film_ior = film.film.ior;
            r.film_thickness = film.film.thickness;
            r.film_f0_metal = film.f0_metal.to_array();
            r.film_metallic = film.metallic;
            r.film_f0 = f0.to_array();
        }
        r
    }

    /// The record the CPU integrator's material would be: `MetallicRoughness` of the
    /// material's evaluated parameters, exactly as `furnace-cpu` builds it per hit.
    pub fn from_material(sample: &furnace_scene::MaterialSample, options: SpecularOptions) -> Self {
        let params = MetallicRoughnessParams {
            base_color: sample.base_color,
            metallic: sample.metallic,
            roughness: sample.roughness,
            specular_factor: sample.specular_factor,
            specular_color: sample.specular_color,
        };
        let m = if sample.iridescence > 0.0 {
            let film = ThinFilm { ior: sample.iridescence_ior, thickness: sample.iridescence_thickness };
            MetallicRoughness::new_iridescent(params, options, sample.iridescence, film)
        } else {
            MetallicRoughness::new(params, options)
        };
        Self::of(&m.with_anisotropy(sample.anisotropy))
    }
}

/// The sheen albedo table `ln E(μ, roughness)` (`furnace_brdf::sheen::SHEEN_LN_E`, row-major),
/// which scenes with a sheen append to [`turquin_table`] (the WGSL reads it from
/// [`TURQUIN_TABLE_LEN`] on).
pub fn sheen_table() -> Vec<f32> {
    furnace_brdf::sheen::SHEEN_LN_E.iter().flatten().copied().collect()
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
