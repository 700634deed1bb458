//! Rust side of the WGSL samplers ([`crate::wgsl::SAMPLING`]): the parameters a shader receives,
//! the sampler codes, and the generated part of the WGSL.
//!
//! # What is twinned
//!
//! `sampling.wgsl` is a twin of `furnace-sampling`:
//!
//! | WGSL | Rust | parity |
//! |---|---|---|
//! | `sampler_bits(p, pixel, index, dim)` | [`Sampler::bits`](furnace_sampling::Sampler::bits) of the [`AnySampler`] that [`SamplerParams::sampler`] builds | bit for bit |
//! | `sampler_bits_2d(…)` (`vec2<u32>`) | [`Sampler::bits_2d`](furnace_sampling::Sampler::bits_2d) | bit for bit |
//! | `sampler_value(…)`, `sampler_value_2d(…)` | [`Sampler::value`](furnace_sampling::Sampler::value), [`Sampler::value_2d`](furnace_sampling::Sampler::value_2d) | bit for bit |
//! | `to_unit_f32(bits)` | [`furnace_sampling::to_unit_f32`] | bit for bit |
//! | `smp_*` helpers (PCG / Kensler / Laine–Karras hashes, Owen scramble and index shuffle, `div_frac`, `isqrt`, Sobol and PMJ02 coordinates) | `furnace_sampling::hash`, `fixed`, [`furnace_sampling::sobol_bits`], [`furnace_sampling::pmj02_coordinate`] | bit for bit |
//! | `warp_concentric_disk`, `warp_uniform_hemisphere`, `warp_cosine_hemisphere` | `furnace_sampling::warp::square_to_*` | same formulas; within the tolerance of `tests/sampler_parity.rs` (WGSL's `sin`, `cos`, `sqrt` and `/` are not correctly rounded) |
//! | `concentric_disk_pdf(p)`, `uniform_hemisphere_pdf(cos θ)`, `cosine_hemisphere_pdf(cos θ)` | `furnace_sampling::warp::*_pdf` (the hemisphere ones take `w` and read `w.z`) | bit for bit on the same input |
//!
//! All five samplers of [`SamplerKind`] are covered, with their pair → dimension mapping (pairs
//! `(2k, 2k+1)` for Hammersley, CMJ and PMJ02, groups of four for Sobol, straddling `bits_2d`
//! at odd / `4k + 3` dimensions) and the index wrapping (`index mod N`) of the fixed-N kinds.
//! Bit-identity is possible because the Rust samplers use wrapping `u32` arithmetic only
//! (ARCHITECTURE.md, rule 2).
//!
//! The tables the WGSL needs (PMJ02's pairing xors, Sobol's direction numbers of dimensions 2
//! and 3), the sampler codes and the `f32` constants of the warps are emitted from the Rust
//! constants by [`wgsl_generated`] and pasted between the `BEGIN GENERATED` / `END GENERATED`
//! lines of `sampling.wgsl`; a test fails, printing the block to paste, if they differ.
//!
//! # How parity is tested
//!
//! `tests/sampler_parity.rs` runs the WGSL on the test adapter (software Vulkan in CI) over more than
//! 10⁵ `(pixel, index, dimension)` triples per sampler — index 0, indices around every 2^k,
//! indices ≥ N for the fixed-N kinds, huge pixel ids, dimensions 0…64 and near 2^32, seeds 0
//! and large, N from 1 to 2^30 — and compares `bits`, `bits_2d`, `value` and `value_2d` bit for
//! bit with the Rust samplers; likewise each helper on random and extreme arguments; the warps
//! within a tolerance stated there; the WGSL layout of [`SamplerParams`] by naga reflection; and
//! that the module declares no bindings.
//!
//! # Using it in a shader
//!
//! Compose [`crate::wgsl::SAMPLING`] first (it needs no other module), put a `SamplerParams` in
//! a uniform buffer, and call e.g. `sampler_value_2d(params, pixel, index, 0u)`. The pixel id
//! and the dimension layout are the integrator's (furnace-cpu: `y * width + x`, dimensions 0–1
//! for the pixel, then four per bounce).

use crate::shared::{WgslType, wgsl_struct};
use furnace_sampling::{AnySampler, PMJ02_XORS, SOBOL_DIRECTIONS, SamplerError, SamplerKind};
use std::fmt::Write as _;

/// The sampler kinds' codes in [`SamplerParams::kind`] (and `SAMPLER_KIND_*` in WGSL): the
/// order of [`SamplerKind`]'s variants, random 0, hammersley 1, cmj 2, pmj02 3, sobol 4.
pub fn kind_code(kind: SamplerKind) -> u32 {
    match kind {
        SamplerKind::Random => 0,
        SamplerKind::Hammersley => 1,
        SamplerKind::Cmj => 2,
        SamplerKind::Pmj02 => 3,
        SamplerKind::Sobol => 4,
    }
}

/// The kind of a code of [`kind_code`]; `None` for an unknown code.
pub fn kind_from_code(code: u32) -> Option<SamplerKind> {
    SamplerKind::ALL.into_iter().find(|&k| kind_code(k) == code)
}

crate::gpu_struct! {
    /// A sampler as a shader receives it: `struct SamplerParams` of `sampling.wgsl`, 16 bytes,
    /// usable in a uniform or storage buffer.
    ///
    /// Build it with [`SamplerParams::new`] from the same `(kind, seed, sample_count)` that
    /// furnace-cpu passes to [`AnySampler::new`] (its `RenderSettings::sampler`, `seed` and
    /// `sample_count`): the WGSL `sampler_bits(params, pixel, index, dim)` then equals
    /// `AnySampler::new(kind, seed, sample_count)?.bits(pixel, index, dim)` bit for bit.
    ///
    /// (Its WGSL declaration is generated from this one: [`wgsl_generated`].)
    #[derive(Eq)]
    pub struct SamplerParams {
        /// [`kind_code`] of the sampler.
        pub kind: u32 => WgslType::U32,
        /// The seed (different seeds give independent images).
        pub seed: u32 => WgslType::U32,
        /// N, the total samples per pixel, for the fixed-N kinds (Hammersley, CMJ; `1 ..= 2^30`);
        /// 0 for the progressive kinds, which ignore it.
        pub sample_count: u32 => WgslType::U32,
        /// Rust-only padding to 16 bytes (a uniform buffer rounds structs up to 16; the WGSL
        /// declaration gets its own); 0.
        pub pad: u32 => WgslType::PAD,
    }
}

const _: () = assert!(size_of::<SamplerParams>() == 16);

// The WGSL has no table for PMJ02's x coordinate: it assumes PMJ02_XORS[0] is all zero.
const _: () = {
    let mut level = 0;
    while level < 32 {
        assert!(PMJ02_XORS[0][level] == 0, "sampling.wgsl assumes PMJ02_XORS[0] is all zero");
        level += 1;
    }
};

impl SamplerParams {
    /// The parameters of the sampler that `AnySampler::new(kind, seed, sample_count)` builds.
    ///
    /// `sample_count` is validated exactly as [`AnySampler::new`] does (same errors): required
    /// by the fixed-N kinds, at most [`furnace_sampling::MAX_SAMPLE_COUNT`]; ignored (stored as
    /// 0) by the progressive ones.
    ///
    /// # Errors
    /// [`SamplerError::MissingSampleCount`] if a fixed-N kind gets `None` or 0,
    /// [`SamplerError::SampleCountTooLarge`] past 2^30.
    pub fn new(kind: SamplerKind, seed: u32, sample_count: Option<u32>) -> Result<Self, SamplerError> {
        let sample_count = match AnySampler::new(kind, seed, sample_count)? {
            AnySampler::Hammersley(s) => s.sample_count(),
            AnySampler::Cmj(s) => s.sample_count(),
            AnySampler::Random(_) | AnySampler::Pmj02(_) | AnySampler::Sobol(_) => 0,
        };
        Ok(Self { kind: kind_code(kind), seed, sample_count, pad: 0 })
    }

    /// The sampler's kind; `None` if [`SamplerParams::kind`] holds an unknown code.
    pub fn sampler_kind(&self) -> Option<SamplerKind> {
        kind_from_code(self.kind)
    }

    /// The CPU twin of these parameters: the [`AnySampler`] whose bits the WGSL reproduces.
    ///
    /// # Errors
    /// [`SamplerError::UnknownKind`] (naming the code) for an unknown code, else those of [`AnySampler::new`]
    /// (a fixed-N kind with `sample_count` 0).
    pub fn sampler(&self) -> Result<AnySampler, SamplerError> {
        let kind =
            self.sampler_kind().ok_or_else(|| SamplerError::UnknownKind(format!("code {}", self.kind)))?;
        AnySampler::new(kind, self.seed, Some(self.sample_count))
    }
}

/// The generated block of `sampling.wgsl` (between its `// BEGIN GENERATED` and
/// `// END GENERATED` lines, exclusive): `struct SamplerParams`, the `SAMPLER_KIND_*` codes ([`kind_code`]), PMJ02's y
/// pairing xors ([`PMJ02_XORS`]`[1]`), Sobol's direction numbers of dimensions 2 and 3
/// ([`SOBOL_DIRECTIONS`]), and the `f32` constants of the warps as Rust rounds them.
///
/// `tests/sampler_parity.rs` checks that the file holds exactly this text.
pub fn wgsl_generated() -> String {
    let mut s = wgsl_struct::<SamplerParams>(false);
    for kind in SamplerKind::ALL {
        let name = kind.name().to_uppercase();
        let _ = writeln!(s, "const SAMPLER_KIND_{name}: u32 = {}u;", kind_code(kind));
    }
    let table = |s: &mut String, comment: &str, name: &str, v: &[u32; 32]| {
        let _ = writeln!(s, "// {comment}");
        let _ = writeln!(s, "const {name} = array<u32, 32>(");
        for row in v.chunks(8) {
            let words: Vec<String> = row.iter().map(|w| format!("0x{w:08x}u")).collect();
            let _ = writeln!(s, "    {},", words.join(", "));
        }
        let _ = writeln!(s, ");");
    };
    table(
        &mut s,
        "furnace_sampling::PMJ02_XORS[1] (the y pairing xors; PMJ02_XORS[0] is all zero).",
        "SMP_PMJ02_XORS_Y",
        &PMJ02_XORS[1],
    );
    table(&mut s, "furnace_sampling::SOBOL_DIRECTIONS[2].", "SMP_SOBOL_DIRECTIONS_2", &SOBOL_DIRECTIONS[2]);
    table(&mut s, "furnace_sampling::SOBOL_DIRECTIONS[3].", "SMP_SOBOL_DIRECTIONS_3", &SOBOL_DIRECTIONS[3]);
    let _ =
        writeln!(s, "// std::f32::consts and warp.rs's rim slack, as Rust rounds them (shortest round-trip");
    let _ = writeln!(s, "// decimal of each f32).");
    use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, TAU};
    // warp.rs: `p.length_squared() <= 1.0 + DISK_RIM_SLACK` with DISK_RIM_SLACK = 1e-6, in f32.
    let disk_rim: f32 = 1.0 + 1e-6;
    for (name, v) in [
        ("SMP_FRAC_1_PI", FRAC_1_PI),
        ("SMP_FRAC_PI_2", FRAC_PI_2),
        ("SMP_FRAC_PI_4", FRAC_PI_4),
        ("SMP_TAU", TAU),
        ("SMP_DISK_RIM", disk_rim),
    ] {
        let _ = writeln!(s, "const {name}: f32 = {v:?}f;");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_follow_the_variant_order() {
        for (i, k) in SamplerKind::ALL.into_iter().enumerate() {
            assert_eq!(kind_code(k), i as u32);
            assert_eq!(kind_code(k), k as u32);
            assert_eq!(kind_from_code(i as u32), Some(k));
        }
        assert_eq!(kind_from_code(5), None);
    }

    #[test]
    fn params_validate_like_any_sampler() {
        let p = SamplerParams::new(SamplerKind::Cmj, 9, Some(64)).unwrap();
        assert_eq!(p, SamplerParams { kind: 2, seed: 9, sample_count: 64, pad: 0 });
        assert_eq!(p.sampler().unwrap(), AnySampler::new(SamplerKind::Cmj, 9, Some(64)).unwrap());
        let p = SamplerParams::new(SamplerKind::Sobol, 3, Some(64)).unwrap();
        assert_eq!(p.sample_count, 0, "progressive kinds ignore N");
        assert_eq!(p.sampler().unwrap(), AnySampler::new(SamplerKind::Sobol, 3, None).unwrap());
        assert!(SamplerParams::new(SamplerKind::Hammersley, 0, None).is_err());
        assert!(SamplerParams::new(SamplerKind::Hammersley, 0, Some(0)).is_err());
        assert!(SamplerParams::new(SamplerKind::Cmj, 0, Some((1 << 30) + 1)).is_err());
        assert!(SamplerParams { kind: 7, seed: 0, sample_count: 0, pad: 0 }.sampler().is_err());
    }
}
