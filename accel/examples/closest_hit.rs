//! Builds a BVH over two triangles and traces a ray and a shadow ray through it:
//! `cargo run --release -p furnace-accel --example closest_hit`.

use furnace_accel::{Bvh, offset_ray_origin};
use glam::Vec3;

fn main() {
    // A floor at y = 0 and a small occluder at y = 0.5 above its centre.
    let triangles = [
        [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)],
        [Vec3::new(-0.1, 0.5, -0.1), Vec3::new(0.1, 0.5, -0.1), Vec3::new(0.0, 0.5, 0.1)],
    ];
    let bvh = Bvh::build(&triangles);
    println!("BVH over {} triangles ({} skipped)", bvh.input_count(), bvh.skipped_count());

    // A ray straight down from y = 2 hits the occluder first, at t = 1.5.
    let (origin, dir) = (Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y);
    let hit = bvh.closest_hit(origin, dir, f32::INFINITY).expect("the ray hits the occluder");
    println!("closest hit: triangle {}, t = {}, barycentrics {}", hit.triangle, hit.t, hit.barycentrics);
    assert_eq!(hit.triangle, 1);
    assert!((hit.t - 1.5).abs() < 1e-6);

    // Off the occluder, the same ray reaches the floor at t = 2.
    let floor = bvh.closest_hit(Vec3::new(0.5, 2.0, -0.5), dir, f32::INFINITY).expect("the floor");
    println!("beside the occluder: triangle {}, t = {}", floor.triangle, floor.t);
    assert_eq!(floor.triangle, 0);

    // A shadow ray from the floor's centre towards a light straight up is blocked.
    let p = offset_ray_origin(Vec3::ZERO, Vec3::Y);
    let blocked = bvh.occluded(p, Vec3::Y, 10.0);
    println!("shadow ray from the floor's centre blocked: {blocked}");
    assert!(blocked);
}
