//! Throughput of each BRDF lobe and sampling method on one thread.
//!
//! `cargo bench -p furnace-brdf` prints a Markdown table (quoted in `BENCHMARKS.md`). Each
//! measurement runs one operation over 1 Mi precomputed inputs — view directions
//! cosine-distributed over the hemisphere, uniform numbers from Owen-scrambled Sobol — and
//! reports the median of 7 runs:
//!
//! * `sample`: `Bsdf::sample(wo, uc, u)` (a path's next bounce; the weight and pdf included);
//! * `eval + pdf`: `Bsdf::eval(wo, wi)` and `Bsdf::pdf(wo, wi)` for a cosine-distributed `wi`
//!   (a light sample with multiple importance sampling);
//! * ns per bounce: one of each, the BSDF cost of one path vertex with next-event estimation.
//!
//! GGX uses α = 0.2 (glTF roughness 0.45). A `--quick` argument runs 1 run of 1/16 the size
//! (a smoke test).

use furnace_brdf::{
    Bsdf, GgxSpecular, Lambert, Masking, MetallicRoughness, MetallicRoughnessParams, Rgb, SpecularOptions,
    SpecularSampling,
};
use furnace_sampling::warp::square_to_cosine_hemisphere;
use furnace_sampling::{OwenSobol, Sampler};
use glam::{Vec2, Vec3};
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

/// Precomputed inputs, so that only the BRDF is timed.
struct Inputs {
    wo: Vec<Vec3>,
    wi: Vec<Vec3>,
    uc: Vec<f32>,
    u: Vec<Vec2>,
}

fn inputs(n: u32) -> Inputs {
    let s = OwenSobol::new(2024);
    let mut v = Inputs { wo: vec![], wi: vec![], uc: vec![], u: vec![] };
    for i in 0..n {
        let [a, b] = s.value_2d(0, i, 0);
        let [c, d] = s.value_2d(0, i, 2);
        let [e, f] = s.value_2d(0, i, 4);
        v.wo.push(square_to_cosine_hemisphere(Vec2::new(a, b)));
        v.u.push(Vec2::new(c, d));
        v.uc.push(e);
        v.wi.push(square_to_cosine_hemisphere(Vec2::new(f, s.value(0, i, 6))));
    }
    v
}

/// Median seconds of `runs` runs of `f`.
fn median_seconds(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// (sample seconds, eval+pdf seconds, fraction of `None`).
fn measure(bsdf: &dyn Bsdf, inp: &Inputs, runs: usize) -> (f64, f64, f64) {
    let n = inp.wo.len();
    let mut rejected = 0usize;
    let t_sample = median_seconds(runs, || {
        let mut acc = Rgb::ZERO;
        rejected = 0;
        for k in 0..n {
            match bsdf.sample(black_box(inp.wo[k]), black_box(inp.uc[k]), black_box(inp.u[k])) {
                Some(s) => acc += s.weight + s.wi * s.pdf,
                None => rejected += 1,
            }
        }
        black_box(acc);
    });
    let t_eval = median_seconds(runs, || {
        let mut acc = Rgb::ZERO;
        for k in 0..n {
            let (wo, wi) = (black_box(inp.wo[k]), black_box(inp.wi[k]));
            acc += bsdf.eval(wo, wi) * bsdf.pdf(wo, wi);
        }
        black_box(acc);
    });
    (t_sample, t_eval, rejected as f64 / n as f64)
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (n, runs) = if quick { (1u32 << 16, 1) } else { (1u32 << 20, 7) };
    let inp = inputs(n);
    let alpha = 0.2;
    let spec = |sampling, masking, compensation| {
        GgxSpecular::new(alpha, Rgb::splat(0.9), SpecularOptions { masking, sampling, compensation })
    };
    let material = |metallic: f32| {
        MetallicRoughness::new(
            MetallicRoughnessParams {
                base_color: Rgb::new(0.8, 0.5, 0.3),
                metallic,
                roughness: alpha.sqrt(),
                ..Default::default()
            },
            SpecularOptions::default(),
        )
    };
    use Masking::{HeightCorrelated as Hc, Separable as Sep};
    use SpecularSampling::{Ndf, SphericalCaps as Caps, Vndf};
    let lobes: Vec<(&str, Box<dyn Bsdf>)> = vec![
        ("Lambert", Box::new(Lambert::new(Rgb::splat(0.8)))),
        ("GGX, NDF (height-corr., no comp.)", Box::new(spec(Ndf, Hc, false))),
        ("GGX, VNDF Heitz 2018 (height-corr., no comp.)", Box::new(spec(Vndf, Hc, false))),
        ("GGX, spherical caps (height-corr., no comp.)", Box::new(spec(Caps, Hc, false))),
        ("GGX, spherical caps, separable G2", Box::new(spec(Caps, Sep, false))),
        ("GGX, spherical caps + Turquin comp.", Box::new(spec(Caps, Hc, true))),
        ("MetallicRoughness, dielectric (default options)", Box::new(material(0.0))),
        ("MetallicRoughness, metallic 0.5", Box::new(material(0.5))),
        ("MetallicRoughness, metal", Box::new(material(1.0))),
    ];
    println!(
        "furnace-brdf throughput, one thread, {} ({n} inputs per run, median of {runs}; GGX α = {alpha})\n",
        cpu_name()
    );
    println!("| lobe | Msamples/s | M(eval+pdf)/s | ns per bounce (sample + eval + pdf) | sample → None |");
    println!("|---|---|---|---|---|");
    for (name, bsdf) in &lobes {
        let (ts, te, rejected) = measure(bsdf.as_ref(), &inp, runs);
        let per = |t: f64| t / n as f64;
        println!(
            "| {name} | {:.1} | {:.1} | {:.1} | {:.1}% |",
            1e-6 / per(ts),
            1e-6 / per(te),
            1e9 * (per(ts) + per(te)),
            100.0 * rejected
        );
    }
}
