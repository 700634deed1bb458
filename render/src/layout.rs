//! The sampler-dimension layout of a path: which dimensions of the sampler each random decision
//! of the integrator reads.
//!
//! | dimensions | use |
//! |---|---|
//! | 0, 1 | position in the pixel ([`DIM_PIXEL`]) |
//! | `2 + 4k`, `3 + 4k` | BSDF direction `u` of scattering event `k = 0, 1, …` ([`bounce`] + [`BOUNCE_BSDF_DIRECTION`]) |
//! | `4 + 4k` | BSDF lobe choice `uc` of event `k` ([`BOUNCE_BSDF_LOBE`]) |
//! | `5 + 4k` | Russian roulette of event `k` ([`BOUNCE_RUSSIAN_ROULETTE`]; unused without it) |
//!
//! Pairs start on even dimensions, so the 2-D samplers (Hammersley, CMJ, PMJ02) stratify the
//! pixel position and each BSDF direction jointly; Owen-Sobol's groups of four put the first
//! BSDF direction with the pixel position.
//!
//! A film holds the samples of one layout: the same sample index under another layout is
//! another path. The layout therefore has a version, [`SAMPLER_LAYOUT_VERSION`], recorded with
//! every saved render; resuming a render of another version is refused
//! ([`crate::resume::check_layout`]). Any change to this table — a new light's dimensions, a
//! reordering — must increase it.

/// The version of the layout below. Version 1 is the layout of every furnace before the version
/// was recorded, so a saved render without a recorded version is of version 1.
pub const SAMPLER_LAYOUT_VERSION: u32 = 1;

/// First of the two dimensions of the camera ray's position inside the pixel.
pub const DIM_PIXEL: u32 = 0;
/// First sampler dimension of the first scattering event.
pub const DIM_FIRST_BOUNCE: u32 = 2;
/// Sampler dimensions used per scattering event: BSDF direction (2), lobe choice (1), Russian
/// roulette (1).
pub const DIMS_PER_BOUNCE: u32 = 4;
/// Offset in an event's dimensions of the two of the BSDF direction.
pub const BOUNCE_BSDF_DIRECTION: u32 = 0;
/// Offset in an event's dimensions of the BSDF lobe choice.
pub const BOUNCE_BSDF_LOBE: u32 = 2;
/// Offset in an event's dimensions of the Russian roulette decision.
pub const BOUNCE_RUSSIAN_ROULETTE: u32 = 3;

const _: () = assert!(BOUNCE_RUSSIAN_ROULETTE < DIMS_PER_BOUNCE && BOUNCE_BSDF_LOBE < DIMS_PER_BOUNCE);
const _: () = assert!(DIM_FIRST_BOUNCE >= DIM_PIXEL + 2, "the pixel takes two dimensions");

/// The first dimension of scattering event `event` (0-based); wraps past `u32::MAX` like the
/// GPU's `u32` arithmetic.
#[inline]
pub const fn bounce(event: u32) -> u32 {
    DIM_FIRST_BOUNCE.wrapping_add(DIMS_PER_BOUNCE.wrapping_mul(event))
}

/// The layout as WGSL `const` declarations (`DIM_PIXEL`, `DIM_FIRST_BOUNCE`, `DIMS_PER_BOUNCE`,
/// `BOUNCE_*`), for shaders that trace the same paths: the GPU integrator composes this instead
/// of declaring its own copy.
pub fn wgsl() -> String {
    [
        ("DIM_PIXEL", DIM_PIXEL),
        ("DIM_FIRST_BOUNCE", DIM_FIRST_BOUNCE),
        ("DIMS_PER_BOUNCE", DIMS_PER_BOUNCE),
        ("BOUNCE_BSDF_DIRECTION", BOUNCE_BSDF_DIRECTION),
        ("BOUNCE_BSDF_LOBE", BOUNCE_BSDF_LOBE),
        ("BOUNCE_RUSSIAN_ROULETTE", BOUNCE_RUSSIAN_ROULETTE),
    ]
    .iter()
    .map(|(name, v)| format!("const {name}: u32 = {v}u;\n"))
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_do_not_overlap() {
        assert_eq!(bounce(0), 2);
        assert_eq!(bounce(1) - bounce(0), DIMS_PER_BOUNCE);
        assert!(bounce(0).is_multiple_of(2), "the BSDF direction pair starts on an even dimension");
        assert!(wgsl().contains("const DIMS_PER_BOUNCE: u32 = 4u;\n"));
    }
}
