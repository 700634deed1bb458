//! The first Owen-scrambled Sobol points of one pixel, and a Monte Carlo estimate of
//! ∫∫ x·y dx dy over the unit square (exactly 1/4) from them:
//! `cargo run --release -p furnace-sampling --example sobol_points`.

use furnace_sampling::{AnySampler, Sampler, SamplerKind};

fn main() {
    // Owen-scrambled Sobol, seed 7; a progressive sampler needs no sample count.
    let sampler = AnySampler::new(SamplerKind::Sobol, 7, None).expect("sobol needs no sample count");
    let pixel = 42;

    println!("first 8 points of pixel {pixel} (dimensions 0 and 1):");
    for index in 0..8 {
        let [u, v] = sampler.value_2d(pixel, index, 0);
        println!("  {index}: ({u:.6}, {v:.6})");
    }

    // Every prefix of the sequence is well distributed: the estimate converges as N grows.
    let mut sum = 0.0f64;
    let mut n = 0u32;
    for log2 in 0..=12 {
        let end = 1u32 << log2;
        for index in n..end {
            let [u, v] = sampler.value_2d(pixel, index, 0);
            sum += f64::from(u) * f64::from(v);
        }
        n = end;
        let estimate = sum / f64::from(n);
        println!("N = {n:5}: estimate {estimate:.6}, error {:+.2e}", estimate - 0.25);
    }
    let estimate = sum / f64::from(n);
    assert!((estimate - 0.25).abs() < 1e-3, "the estimate {estimate} should be close to 0.25");
}
