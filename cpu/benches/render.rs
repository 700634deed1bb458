//! Path-tracing throughput of the CPU integrator.
//!
//! `cargo bench -p furnace-cpu` renders the built-in reference Cornell box at 256×256 with 4
//! bounces on a 2-thread rayon pool (the developers' machine has 2 cores; Mitsuba 3 on such a
//! machine: `scalar_rgb` 1.87, `llvm_ad_rgb` 5.25 Msamples/s, `shared/references/README.md`)
//! and prints Msamples/s (camera paths per second, not rays) for the random and Sobol samplers:
//! the best of 3 passes of 16 samples per pixel, after a warm-up pass.
//!
//! Flags: `--quick` (one pass of 4 samples per pixel), `--threads N`, `--bounces B`.

use furnace_cpu::{RenderSettings, Renderer};
use furnace_sampling::SamplerKind;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let flag = |name: &str, default: u32| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let (threads, bounces) = (flag("--threads", 2), flag("--bounces", 4));
    let (passes, spp) = if quick { (1, 4) } else { (3, 16) };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads as usize).build().expect("a thread pool");
    println!("| scene | size | bounces | sampler | threads | spp/pass | Msamples/s |");
    println!("|---|---|---|---|---|---|---|");
    for sampler in [SamplerKind::Random, SamplerKind::Sobol] {
        let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
        let settings = RenderSettings { width: 256, height: 256, bounces, sampler, ..Default::default() };
        let renderer = Renderer::new(scene, settings).expect("a progressive sampler");
        let mut film = renderer.new_film();
        pool.install(|| renderer.render_pass(&mut film, 0, 1)).expect("render");
        let mut best = 0.0f64;
        for pass in 0..passes {
            let start = Instant::now();
            pool.install(|| renderer.render_pass(&mut film, 1 + pass * spp, spp)).expect("render");
            let samples = f64::from(settings.width * settings.height * spp);
            best = best.max(samples / start.elapsed().as_secs_f64() / 1e6);
        }
        println!("| cbox | 256×256 | {bounces} | {sampler} | {threads} | {spp} | {best:.2} |");
    }
}
