//! Throughput of each sampler: 2-D points per second on one thread.
//!
//! `cargo bench -p furnace-sampling` prints a Markdown table (quoted in `BENCHMARKS.md`).
//! Each measurement evaluates `bits_2d` for 1024 pixels × 1024 sample indices (1 Mi points) at
//! dimensions (0,1) and at (6,7) — pairs past the first cost more for the samplers that shuffle
//! the index — and reports the median of 7 runs. A `--quick` argument runs 1 run of 1/16 the
//! size (a smoke test).

use furnace_sampling::{AnySampler, Sampler, SamplerKind};
use std::hint::black_box;
use std::time::Instant;

fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn points_per_second(sampler: &AnySampler, dim: u32, pixels: u32, spp: u32, runs: usize) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            let mut acc = 0u32;
            for pixel in 0..pixels {
                for index in 0..spp {
                    let [a, b] = sampler.bits_2d(black_box(pixel), black_box(index), black_box(dim));
                    acc = acc.wrapping_add(a ^ b);
                }
            }
            black_box(acc);
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    (pixels as f64 * spp as f64) / times[times.len() / 2]
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (pixels, spp, runs) = if quick { (256, 256, 1) } else { (1024, 1024, 7) };
    println!(
        "furnace-sampling throughput, one thread, {} ({} pixels × {} spp per run, median of {runs})\n",
        cpu_name(),
        pixels,
        spp
    );
    println!("| sampler | Mpoints/s dims (0,1) | Mpoints/s dims (6,7) | ns/point (0,1) |");
    println!("|---|---|---|---|");
    for kind in SamplerKind::ALL {
        let s = AnySampler::new(kind, 1, Some(spp)).expect("valid sampler");
        let first = points_per_second(&s, 0, pixels, spp, runs);
        let later = points_per_second(&s, 6, pixels, spp, runs);
        println!("| {kind} | {:.1} | {:.1} | {:.2} |", first / 1e6, later / 1e6, 1e9 / first);
    }
}
