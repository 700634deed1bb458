//! Tone-maps a few linear radiances with ACES and Khronos PBR Neutral and encodes them as
//! 8-bit sRGB: `cargo run --release -p furnace-post --example tonemap`.

use furnace_post::{Tonemap, to_srgb8};
use glam::Vec3;

fn main() {
    let radiance =
        [Vec3::ZERO, Vec3::splat(0.18), Vec3::splat(1.0), Vec3::new(4.0, 1.0, 0.25), Vec3::splat(100.0)];
    for tonemap in [Tonemap::Aces, Tonemap::PbrNeutral] {
        // Exposure 0 EV: radiance unchanged before the tone map.
        let srgb = to_srgb8(&radiance, 0.0, tonemap);
        println!("{}:", tonemap.name());
        for (l, c) in radiance.iter().zip(&srgb) {
            println!("  {l:>16} -> {c:?}");
        }
        // Black stays black; brighter grey never gives a darker code.
        assert_eq!(srgb[0], [0, 0, 0]);
        assert!(srgb[1][0] < srgb[2][0] && srgb[2][0] <= srgb[4][0]);
    }
    // ACES(0.18) = 0.2669, sRGB-encoded 0.5534: code 141.
    assert_eq!(to_srgb8(&radiance[1..2], 0.0, Tonemap::Aces)[0], [141, 141, 141]);
}
