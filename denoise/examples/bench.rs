//! Times `denoise` at 512² and 1920×1080, without guides, with albedo + normal, and with
//! prefiltered albedo + normal, on the synthetic scene of the tests (16-sample-like noise):
//!
//! ```text
//! OIDN_DIR=… cargo run --release -p furnace-denoise --features oidn --example bench -- [DEVICE] [REPS] [QUALITY] [SIZES]
//! ```
//!
//! SIZES: comma-separated `WxH` (default `512x512,1920x1080`).
//! DEVICE: `default` (the default), `cpu`, `cuda`, `hip`, `sycl`, `metal`; REPS: runs per case
//! (default 3; the best and the median are printed); QUALITY: `default`, `fast`, `balanced`,
//! `high`. Also prints each result's RMSE against the clean image, so a fast but wrong run shows.
//! Without the `oidn` feature it prints why it cannot run.

#[path = "../tests/synthetic/mod.rs"]
mod synthetic;

use furnace_denoise::{DeviceKind, Guides, Options, Quality, denoise};
use synthetic::{Scene, rmse};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let device = match args.first().map(String::as_str).unwrap_or("default") {
        "default" => DeviceKind::Default,
        "cpu" => DeviceKind::Cpu,
        "cuda" => DeviceKind::Cuda,
        "hip" => DeviceKind::Hip,
        "sycl" => DeviceKind::Sycl,
        "metal" => DeviceKind::Metal,
        other => panic!("unknown device {other:?}"),
    };
    let reps: usize = args.get(1).map_or(3, |r| r.parse().expect("REPS: a number"));
    let quality = match args.get(2).map(String::as_str).unwrap_or("default") {
        "default" => Quality::Default,
        "fast" => Quality::Fast,
        "balanced" => Quality::Balanced,
        "high" => Quality::High,
        other => panic!("unknown quality {other:?}"),
    };
    let threads = std::thread::available_parallelism().map_or(0, |n| n.get());
    println!("device {device:?}, quality {quality:?}, {reps} runs per case, {threads} hardware threads");
    println!(
        "{:>10}  {:<22} {:>12} {:>12} {:>12} {:>10}  {:>8}  device",
        "size", "guides", "best s", "median s", "prefilter s", "device s", "RMSE"
    );
    let sizes: Vec<(u32, u32)> = args
        .get(3)
        .map_or("512x512,1920x1080", String::as_str)
        .split(',')
        .map(|s| {
            let (w, h) = s.split_once('x').expect("SIZES: WxH,…");
            (w.parse().expect("a width"), h.parse().expect("a height"))
        })
        .collect();
    for (w, h) in sizes {
        let scene = Scene::new(w, h);
        let noisy = scene.noisy(16, 1);
        let both = Guides { albedo: Some(&scene.albedo), normal: Some(&scene.normal) };
        for (name, guides, prefilter_guides) in [
            ("none", Guides::NONE, false),
            ("albedo+normal", both, false),
            ("albedo+normal, prefilt.", both, true),
        ] {
            let options = Options { device, quality, prefilter_guides, ..Options::default() };
            let mut runs = Vec::new();
            for _ in 0..reps.max(1) {
                match denoise(w, h, &noisy, guides, &options) {
                    Ok(out) => runs.push(out),
                    Err(e) => {
                        eprintln!("{e}");
                        std::process::exit(1);
                    }
                }
            }
            runs.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
            let (best, median) = (&runs[0], &runs[runs.len() / 2]);
            println!(
                "{:>10}  {:<22} {:>12.3} {:>12.3} {:>12.3} {:>10.4}  {:>8.4}  {}",
                format!("{w}x{h}"),
                name,
                best.seconds,
                median.seconds,
                best.prefilter_seconds,
                best.device_seconds,
                rmse(w, &best.pixels, &scene.clean, None),
                best.device
            );
        }
    }
}
