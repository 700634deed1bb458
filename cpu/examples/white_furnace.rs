//! A white furnace: a Lambert sphere of albedo 1 under a sky of radiance 1, rendered with the
//! CPU reference integrator, looks exactly like the sky (every pixel ≈ 1):
//! `cargo run --release -p furnace-cpu --example white_furnace`.

use furnace_cpu::CpuRenderer;
use furnace_render::{Integrator, RenderError, RenderSettings};
use furnace_scene::builtin;
use glam::{DVec3, Vec3};

fn main() -> Result<(), RenderError> {
    let scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 32);
    let settings = RenderSettings { width: 32, height: 32, ..Default::default() };
    let mut renderer = CpuRenderer::with_default_camera(scene, settings)?;
    renderer.render_pass(0, 16)?;
    let film = renderer.film()?;

    let centre = film.pixel(16, 16);
    // On the silhouette of the tessellated sphere a sampled direction can be above the shading
    // normal's horizon but below the facet's; such a path ends, so those pixels are a little dark.
    let pixels = (film.width() * film.height()) as usize;
    let exact = (0..pixels).filter(|&i| (film.mean(i) - DVec3::ONE).abs().max_element() < 1e-3).count();
    println!("centre pixel (on the sphere): {centre}");
    println!("pixels within 1e-3 of 1: {exact} of {pixels}");
    assert!((centre - DVec3::ONE).abs().max_element() < 1e-3);
    assert_eq!(film.rejected(), 0);
    Ok(())
}
