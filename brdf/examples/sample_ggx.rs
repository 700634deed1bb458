//! Samples a GGX lobe with an Owen-scrambled Sobol sequence and estimates its directional
//! albedo (the mean of the sample weights `eval/pdf`):
//! `cargo run --release -p furnace-brdf --example sample_ggx`.

use furnace_brdf::{Bsdf, GgxSpecular, SpecularOptions};
use furnace_sampling::{OwenSobol, Sampler};
use glam::{Vec2, Vec3};

fn main() {
    // A white metal (F0 = 1), GGX alpha 0.5, without energy compensation: single scattering
    // loses some energy, so the albedo is below 1.
    let options = SpecularOptions { compensation: false, ..SpecularOptions::default() };
    let lobe = GgxSpecular::new(0.5, Vec3::ONE, options);
    let sampler = OwenSobol::new(1);
    let n = 1u32 << 16;

    for cos_theta in [1.0f32, 0.7, 0.3, 0.1] {
        let wo = Vec3::new((1.0 - cos_theta * cos_theta).sqrt(), 0.0, cos_theta);
        let mut sum = 0.0f64;
        for index in 0..n {
            // Dimension 0: the lobe choice (unused by a single lobe); 1 and 2: the direction.
            let uc = sampler.value(0, index, 0);
            let u = Vec2::from(sampler.value_2d(0, index, 1));
            if let Some(s) = lobe.sample(wo, uc, u) {
                sum += f64::from(s.weight.x);
            }
        }
        let albedo = sum / f64::from(n);
        println!("cos θo = {cos_theta:.1}: directional albedo {albedo:.4}");
        assert!(albedo > 0.0 && albedo <= 1.0, "albedo {albedo} should be in (0, 1]");
    }
}
