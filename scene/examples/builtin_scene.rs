//! Prints the statistics, lights and camera of the built-in Cornell box (no file needed):
//! `cargo run --release -p furnace-scene --example builtin_scene`.

use furnace_scene::builtin;

fn main() -> Result<(), furnace_scene::SceneError> {
    let scene = builtin::cornell_box()?;
    let stats = scene.stats();
    println!(
        "{}: {} triangles, {} vertices, {} materials",
        scene.name, stats.triangles, stats.vertices, stats.materials
    );
    println!(
        "  {:.1} bytes per triangle, {} degenerate triangles dropped",
        stats.bytes_per_triangle, stats.dropped_triangles
    );
    for light in &scene.lights {
        println!("  light: {light}");
    }
    let camera = scene.default_camera();
    println!("  camera at {}", camera.world_from_camera.translation);
    for w in &scene.warnings {
        println!("  warning: {w}");
    }
    assert_eq!(stats.triangles, 20_516);
    assert!(scene.sun().is_some());
    Ok(())
}
