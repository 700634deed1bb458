//! The sampler-dimension layout of a path: which dimensions of the sampler each random decision
//! of the integrator reads.
//!
//! | dimensions | use |
//! |---|---|
//! | 0, 1 | position in the pixel ([`DIM_PIXEL`]) |
//! | `2 + 4k`, `3 + 4k` | BSDF direction `u` of scattering event `k = 0, 1, …` ([`bounce`] + [`BOUNCE_BSDF_DIRECTION`]) |
//! | `4 + 4k` | BSDF lobe choice `uc` of event `k` ([`BOUNCE_BSDF_LOBE`]) |
//! | `5 + 4k` | Russian roulette of event `k` ([`BOUNCE_RUSSIAN_ROULETTE`]; unused without it) |
//! | `L + 8k`, `L + 1 + 8k` | point on the emitter chosen at event `k` ([`light`] + [`LIGHT_EMITTER_POINT`]) |
//! | `L + 2 + 8k` | the emitter's bin in the alias table, 32 bits ([`LIGHT_EMITTER_BIN`]) |
//! | `L + 3 + 8k` | the alias table's coin ([`LIGHT_EMITTER_COIN`]) |
//! | `L + 4 + 8k`, `L + 5 + 8k` | direction in the sun's disc ([`LIGHT_SUN_DISC`]) |
//! | `L + 6 + 8k`, `L + 7 + 8k` | the environment map's light sample: row, then column ([`LIGHT_ENVIRONMENT`]) |
//! | `P + k` | the point or spot light chosen at event `k` (`--point-lights one`; [`point_light`]) |
//! | `W` | the path's wavelength, drawn at its first dispersive solid ([`wavelength`]) |
//!
//! where `L = 4·(bounces + 1)` ([`light_block`]) is the first group of four after every
//! event's BSDF dimensions and `P = L + 8·bounces` ([`point_light_block`]) the first after the
//! light block (light samples are taken at events `0 … bounces − 1`), and `W = P + bounces` the
//! one after the point-light choices. The light dimensions come
//! after the whole BSDF block, not interleaved with it, so that a scene that samples no light
//! (no emitters, no sun disc) reads exactly the dimensions it read before they existed: its
//! images are the same bits; the point-light choices come after both, for the same reason.
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
/// was recorded, so a saved render without a recorded version is of version 1. Version 2 added
/// the light block, version 3 the point-light choices, version 4 the wavelength; none changed a
/// dimension of the versions before, so a render of an earlier version that reads none of the added dimensions
/// is a render of this one too ([`crate::resume::check_layout`]).
pub const SAMPLER_LAYOUT_VERSION: u32 = 4;

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

/// Sampler dimensions of the light block per scattering event.
pub const LIGHT_DIMS_PER_EVENT: u32 = 8;
/// Offset in an event's light dimensions of the two of the point on the chosen emitter.
pub const LIGHT_EMITTER_POINT: u32 = 0;
/// Offset of the 32 bits that choose the emitter's alias-table bin.
pub const LIGHT_EMITTER_BIN: u32 = 2;
/// Offset of the alias table's coin.
pub const LIGHT_EMITTER_COIN: u32 = 3;
/// Offset of the two dimensions of the direction inside a sun's disc.
pub const LIGHT_SUN_DISC: u32 = 4;
/// Offset of the two dimensions of an environment map's light sample (the first chooses the
/// column within the row, the second the row: `Distribution2D::sample`'s `u.x`, `u.y`).
pub const LIGHT_ENVIRONMENT: u32 = 6;

const _: () = assert!(LIGHT_SUN_DISC + 2 <= LIGHT_ENVIRONMENT && LIGHT_EMITTER_COIN < LIGHT_SUN_DISC);
const _: () = assert!(LIGHT_ENVIRONMENT + 2 <= LIGHT_DIMS_PER_EVENT && LIGHT_ENVIRONMENT.is_multiple_of(2));
// The bin and the coin are drawn as one pair (an even dimension, then the next).
const _: () = assert!(LIGHT_EMITTER_COIN == LIGHT_EMITTER_BIN + 1 && LIGHT_EMITTER_BIN.is_multiple_of(2));

/// The first dimension of the light block of a render of `bounces` scattering events:
/// `4·(bounces + 1)`, past the last BSDF dimension `bounce(bounces − 1) + 3 = 4·bounces + 1`
/// and on a group of four (Owen-Sobol's 4-D padding). Wraps like the GPU's `u32`.
#[inline]
pub const fn light_block(bounces: u32) -> u32 {
    4u32.wrapping_mul(bounces.wrapping_add(1))
}

/// The first light dimension of scattering event `event` of a render of `bounces` events.
#[inline]
pub const fn light(bounces: u32, event: u32) -> u32 {
    light_block(bounces).wrapping_add(LIGHT_DIMS_PER_EVENT.wrapping_mul(event))
}

/// The first dimension of the point-light choices of a render of `bounces` scattering events:
/// `4·(bounces + 1) + 8·bounces`, past the light dimensions of the last event that takes light
/// samples (event `bounces − 1`). Wraps like the GPU's `u32`.
#[inline]
pub const fn point_light_block(bounces: u32) -> u32 {
    light_block(bounces).wrapping_add(LIGHT_DIMS_PER_EVENT.wrapping_mul(bounces))
}

/// The dimension that chooses the point or spot light of scattering event `event` of a render
/// of `bounces` events (one dimension per event: consecutive events share Owen-Sobol's groups
/// of four and the 2-D samplers' pairs, as independent dimensions of one point).
#[inline]
pub const fn point_light(bounces: u32, event: u32) -> u32 {
    point_light_block(bounces).wrapping_add(event)
}

/// The dimension of the path's wavelength in a render of `bounces` scattering events (one per
/// path, drawn where it first meets a dispersive solid): past the point-light choices. Wraps
/// like the GPU's `u32`.
#[inline]
pub const fn wavelength(bounces: u32) -> u32 {
    point_light_block(bounces).wrapping_add(bounces)
}

/// The layout as WGSL `const` declarations (`DIM_PIXEL`, `DIM_FIRST_BOUNCE`, `DIMS_PER_BOUNCE`,
/// `BOUNCE_*`, `LIGHT_*`; the light block's start is `4u * (bounces + 1u)`), for shaders that trace the same paths: the GPU integrator composes this instead
/// of declaring its own copy.
pub fn wgsl() -> String {
    [
        ("DIM_PIXEL", DIM_PIXEL),
        ("DIM_FIRST_BOUNCE", DIM_FIRST_BOUNCE),
        ("DIMS_PER_BOUNCE", DIMS_PER_BOUNCE),
        ("BOUNCE_BSDF_DIRECTION", BOUNCE_BSDF_DIRECTION),
        ("BOUNCE_BSDF_LOBE", BOUNCE_BSDF_LOBE),
        ("BOUNCE_RUSSIAN_ROULETTE", BOUNCE_RUSSIAN_ROULETTE),
        ("LIGHT_DIMS_PER_EVENT", LIGHT_DIMS_PER_EVENT),
        ("LIGHT_EMITTER_POINT", LIGHT_EMITTER_POINT),
        ("LIGHT_EMITTER_BIN", LIGHT_EMITTER_BIN),
        ("LIGHT_EMITTER_COIN", LIGHT_EMITTER_COIN),
        ("LIGHT_SUN_DISC", LIGHT_SUN_DISC),
        ("LIGHT_ENVIRONMENT", LIGHT_ENVIRONMENT),
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

    #[test]
    fn the_light_block_follows_every_bsdf_dimension() {
        for bounces in [0, 1, 4, 100] {
            let last_bsdf =
                if bounces == 0 { DIM_PIXEL + 1 } else { bounce(bounces - 1) + DIMS_PER_BOUNCE - 1 };
            assert!(light_block(bounces) > last_bsdf);
            assert!(light_block(bounces).is_multiple_of(4));
            assert_eq!(light(bounces, 1) - light(bounces, 0), LIGHT_DIMS_PER_EVENT);
        }
    }

    #[test]
    fn the_point_light_choices_follow_every_light_dimension() {
        for bounces in [1, 4, 100] {
            let last_light = light(bounces, bounces - 1) + LIGHT_DIMS_PER_EVENT - 1;
            assert_eq!(point_light_block(bounces), last_light + 1);
            assert!(point_light_block(bounces).is_multiple_of(4));
            assert_eq!(point_light(bounces, bounces - 1), point_light_block(bounces) + bounces - 1);
        }
    }
}
