//! Path-tracing throughput of the CPU integrator.
//!
//! `cargo bench -p furnace-cpu` renders the built-in reference Cornell box at 256×256 with 4
//! bounces on a 2-thread rayon pool (the developers' machine has 2 cores; against Mitsuba 3 and
//! Cycles compare only side by side, with `docs/bench/cpu-peers.sh`) and prints Msamples/s
//! (camera paths per second, not rays) for the random and Sobol samplers: the best of 3 passes
//! of 16 samples per pixel, after a warm-up pass.
//!
//! Flags: `--quick` (one pass of 4 samples per pixel), `--threads N`, `--bounces B`,
//! `--size S` (S×S pixels), `--spp N` (samples per pixel per pass), `--passes N`,
//! `--sampler NAME` (only that sampler, e.g. `sobol`), `--checksum` (print a hash of the
//! film's bits after the passes: equal hashes mean bit-identical images).
//!
//! Profiling: `valgrind --tool=callgrind --toggle-collect='*render_pass*'` on
//! `--threads 1 --size 64 --spp 4 --passes 1 --sampler sobol` counts the instructions of
//! rendering alone (not the BVH build), deterministically (`BENCHMARKS.md`).

use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let checksum = args.iter().any(|a| a == "--checksum");
    let value = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1));
    let flag = |name: &str, default: u32| value(name).and_then(|s| s.parse().ok()).unwrap_or(default);
    let (threads, bounces, size) = (flag("--threads", 2), flag("--bounces", 4), flag("--size", 256));
    let (passes, spp) = if quick { (1, 4) } else { (3, 16) };
    let (passes, spp) = (flag("--passes", passes), flag("--spp", spp));
    let samplers: Vec<SamplerKind> = match value("--sampler") {
        Some(name) => vec![name.parse().expect("a sampler name")],
        None => vec![SamplerKind::Random, SamplerKind::Sobol],
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads as usize).build().expect("a thread pool");
    println!("| scene | size | bounces | sampler | threads | spp/pass | Msamples/s |");
    println!("|---|---|---|---|---|---|---|");
    for sampler in samplers {
        let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
        let settings = RenderSettings { width: size, height: size, bounces, sampler, ..Default::default() };
        let renderer = CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler");
        let mut film = renderer.new_film();
        pool.install(|| renderer.render_into(&mut film, 0, 1)).expect("render");
        let mut best = 0.0f64;
        for pass in 0..passes {
            let start = Instant::now();
            pool.install(|| renderer.render_into(&mut film, 1 + pass * spp, spp)).expect("render");
            let samples = f64::from(settings.width * settings.height * spp);
            best = best.max(samples / start.elapsed().as_secs_f64() / 1e6);
        }
        println!("| cbox | {size}×{size} | {bounces} | {sampler} | {threads} | {spp} | {best:.2} |");
        if checksum {
            // FNV-1a over every pixel's mean, as f64 bits.
            let mut hash = 0xcbf2_9ce4_8422_2325u64;
            for y in 0..size {
                for x in 0..size {
                    for c in film.pixel(x, y).to_array() {
                        hash = (hash ^ c.to_bits()).wrapping_mul(0x0000_0100_0000_01b3);
                    }
                }
            }
            println!("checksum {sampler}: {hash:016x}");
        }
    }
}
