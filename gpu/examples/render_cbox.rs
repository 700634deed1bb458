//! Renders the built-in Cornell box at 64×64, 16 samples per pixel, on the best GPU adapter
//! and prints the image mean: `cargo run --release -p furnace-gpu --example render_cbox`.
//! Without an adapter it prints why and exits successfully.

use furnace_gpu::{AdapterChoice, GpuContext, GpuRenderer};
use furnace_render::RenderSettings;
use glam::DVec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ctx = match GpuContext::new(&AdapterChoice::Best) {
        Ok(ctx) => ctx,
        Err(e) => {
            println!("no GPU to render on: {e}");
            return Ok(());
        }
    };
    println!("adapter: {}", ctx.describe());
    let scene = furnace_scene::builtin::cornell_box()?;
    let settings = RenderSettings { width: 64, height: 64, ..Default::default() };
    let mut gpu = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings)?;
    gpu.render_pass(0, 16)?; // samples 0..16 of every pixel
    let film = gpu.film()?;

    let pixels = (film.width() * film.height()) as usize;
    let mean = (0..pixels).map(|i| film.mean(i)).sum::<DVec3>() / pixels as f64;
    println!("64×64, 16 spp: image mean {mean:.4}, {} rejected samples", film.rejected());
    assert!(mean.is_finite() && mean.min_element() > 0.0, "a lit Cornell box is not black");
    assert_eq!(film.sample_count(32, 32), 16);
    Ok(())
}
