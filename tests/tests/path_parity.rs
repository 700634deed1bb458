//! The integrator's per-path WGSL pieces (`furnace_gpu::wgsl::PATH`) against their Rust twins,
//! on the same inputs: the camera ray (`Camera::generate_ray`, perspective and orthographic,
//! square and wide images, film points inside and on the edges of the image), the shading
//! frame (`furnace_brdf::Frame`, normals near both poles, on the equator, `n.z = ±0.0`) and
//! Russian roulette's survival probability (`furnace_render::russian_roulette_survival`).
//!
//! Tolerances: the GPU may contract multiply-adds into FMAs (the H100's Vulkan driver does) and
//! its `normalize` may use an inverse square root of 2 ULP, so camera ray origins are compared
//! within 4 ULP of the largest term that forms them (camera position and film extent),
//! directions within 2e-6 (unit vectors: a few ULP), frame vectors within 2e-6 of unit length.
//! The survival probability is a min/max of the inputs: exact. Lavapipe gives bit-identical
//! results; the count of bit-identical values is printed.

use furnace_gpu::integrator::{FrameParams, frame_flags_wgsl, frame_params};
use furnace_gpu::sampling::SamplerParams;
use furnace_gpu::shared::wgsl_struct;
use furnace_gpu::wgsl;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_scene::{Camera, Projection, builtin};
use furnace_tests::Rng;
use furnace_tests::gpu::{self as kernel, test_context};
use glam::{Affine3A, Quat, Vec2, Vec3};

/// The bindings of the path kernels: the kernel harness's input and output, and the uniform
/// block as a storage buffer at binding 3 (`params`, read by `path.wgsl`).
fn shader(main: &str) -> String {
    let generated =
        [frame_flags_wgsl(), wgsl_struct::<SamplerParams>(false), wgsl_struct::<FrameParams>(true)].concat();
    wgsl::compose(&[
        &generated,
        r#"
@group(0) @binding(0) var<storage, read> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@group(0) @binding(2) var<uniform> kernel_params: vec4<u32>;
@group(0) @binding(3) var<storage, read> params: FrameParams;

fn index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}
"#,
        &wgsl::select(wgsl::PATH, |_| true),
        main,
    ])
}

const CAMERA_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= kernel_params.x { return; }
    let ray = camera_ray(vec2<f32>(bitcast<f32>(input[2u * i]), bitcast<f32>(input[2u * i + 1u])));
    for (var c = 0u; c < 3u; c++) {
        output[6u * i + c] = bitcast<u32>(ray.origin[c]);
        output[6u * i + 3u + c] = bitcast<u32>(ray.direction[c]);
    }
}
"#;

const FRAME_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= kernel_params.x { return; }
    let n = vec3<f32>(bitcast<f32>(input[3u * i]), bitcast<f32>(input[3u * i + 1u]), bitcast<f32>(input[3u * i + 2u]));
    let f = frame_new(n);
    // A fixed vector to local and back, as the integrator uses the frame.
    let v = vec3<f32>(0.36, -0.48, 0.8);
    let local = frame_to_local(f, v);
    let world = frame_to_world(f, local);
    let out = array<vec3<f32>, 4>(f.x, f.y, local, world);
    for (var k = 0u; k < 4u; k++) {
        for (var c = 0u; c < 3u; c++) {
            output[12u * i + 3u * k + c] = bitcast<u32>(out[k][c]);
        }
    }
}
"#;

const TANGENT_FRAME_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= kernel_params.x { return; }
    var w: array<vec3<f32>, 2>;
    for (var k = 0u; k < 2u; k++) {
        let b = 6u * i + 3u * k;
        w[k] = vec3<f32>(bitcast<f32>(input[b]), bitcast<f32>(input[b + 1u]), bitcast<f32>(input[b + 2u]));
    }
    let f = frame_with_tangent(w[0], w[1]);
    let out = array<vec3<f32>, 2>(f.x, f.y);
    for (var k = 0u; k < 2u; k++) {
        for (var c = 0u; c < 3u; c++) {
            output[6u * i + 3u * k + c] = bitcast<u32>(out[k][c]);
        }
    }
}
"#;

const ROULETTE_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= kernel_params.x { return; }
    let t = vec3<f32>(bitcast<f32>(input[3u * i]), bitcast<f32>(input[3u * i + 1u]), bitcast<f32>(input[3u * i + 2u]));
    output[i] = bitcast<u32>(russian_roulette_survival(t));
}
"#;

fn words(params: &FrameParams) -> Vec<u32> {
    bytemuck::cast_slice(bytemuck::bytes_of(params)).to_vec()
}

/// Compares `got` with `want` within `tol`; returns whether the bits were equal.
fn close(what: &str, got: Vec3, want: Vec3, tol: f32) -> bool {
    assert!(
        (got - want).abs().max_element() <= tol,
        "{what}: GPU {got:?} vs Rust {want:?} (difference {:?}, tolerance {tol:e})",
        got - want
    );
    got.to_array().map(f32::to_bits) == want.to_array().map(f32::to_bits)
}

fn vec3_at(out: &[u32], k: usize) -> Vec3 {
    Vec3::new(f32::from_bits(out[k]), f32::from_bits(out[k + 1]), f32::from_bits(out[k + 2]))
}

#[test]
fn camera_rays_match_generate_ray() {
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().expect("the built-in Cornell box");
    // Perspective (the box's own camera, and a tilted one far from the origin) and
    // orthographic cameras, rotated about every axis.
    let rotation = Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.2);
    let cameras = [
        ("cbox camera", scene.default_camera()),
        (
            "perspective, tilted, at 1e3",
            Camera {
                world_from_camera: Affine3A::from_rotation_translation(rotation, Vec3::new(1e3, -2e2, 5e2)),
                projection: Projection::Perspective { yfov: 1.3, aspect_ratio: None },
            },
        ),
        (
            "orthographic",
            Camera {
                world_from_camera: Affine3A::from_rotation_translation(rotation, Vec3::new(-3.0, 4.0, 12.0)),
                projection: Projection::Orthographic { xmag: 2.0, ymag: 1.5 },
            },
        ),
    ];
    let sampler = SamplerParams::new(SamplerKind::Random, 0, None).expect("the random sampler");
    let mut rng = Rng(31);
    let (mut identical, mut total) = (0, 0);
    for (name, camera) in cameras {
        for (width, height) in [(256u32, 256u32), (1920, 1080), (7, 3)] {
            let settings = RenderSettings { width, height, ..Default::default() };
            let params = frame_params(&scene, &camera, &settings, sampler);
            // Film points: random inside the image, plus its corners and centre.
            let (w, h) = (width as f32, height as f32);
            let mut points: Vec<Vec2> =
                (0..4000).map(|_| Vec2::new(rng.range(0.0, w), rng.range(0.0, h))).collect();
            points.extend([
                Vec2::ZERO,
                Vec2::new(w, 0.0),
                Vec2::new(0.0, h),
                Vec2::new(w, h),
                Vec2::new(w, h) * 0.5,
            ]);
            let input: Vec<u32> = points.iter().flat_map(|p| [p.x.to_bits(), p.y.to_bits()]).collect();
            let out = kernel::run_with(
                &ctx,
                &shader(CAMERA_KERNEL),
                &input,
                &[&words(&params)],
                6 * points.len(),
                points.len() as u32,
            )
            .expect("the camera kernel");
            let extent = match camera.projection {
                Projection::Perspective { .. } => 0.0,
                Projection::Orthographic { ymag, .. } => ymag * w / h,
            };
            let scale = camera.world_from_camera.translation.abs().max_element() + extent;
            for (k, p) in points.iter().enumerate() {
                let want = camera.generate_ray(*p, width, height);
                let what = format!("{name}, {width}×{height}, film point {p}");
                identical += usize::from(close(
                    &format!("{what}: origin"),
                    vec3_at(&out, 6 * k),
                    want.origin,
                    4.0 * f32::EPSILON * scale.max(1.0),
                ));
                identical += usize::from(close(
                    &format!("{what}: direction"),
                    vec3_at(&out, 6 * k + 3),
                    want.direction,
                    2e-6,
                ));
                total += 2;
            }
        }
    }
    println!("camera rays: {identical} of {total} vectors bit-identical");
}

#[test]
fn frames_match_furnace_brdf() {
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(32);
    let mut normals: Vec<Vec3> = (0..20_000).map(|_| rng.unit_vector()).collect();
    // The poles and near them (the branch of `copysign`), the equator, signed zeros.
    for z in [1.0f32, -1.0, 0.0, -0.0, 1e-7, -1e-7, 1.0 - 1e-7, -1.0 + 1e-7] {
        for k in 0..16 {
            let phi = k as f32 * std::f32::consts::TAU / 16.0;
            let r = (1.0 - z * z).max(0.0).sqrt();
            normals.push(Vec3::new(r * phi.cos(), r * phi.sin(), z).normalize());
        }
    }
    normals.extend(
        [Vec3::new(0.0, 0.0, -0.0), Vec3::Z, Vec3::NEG_Z]
            .map(|n| if n.length() == 0.0 { Vec3::new(1.0, 0.0, -0.0) } else { n }),
    );
    let input: Vec<u32> = normals.iter().flat_map(|n| n.to_array().map(f32::to_bits)).collect();
    let sampler = SamplerParams::new(SamplerKind::Random, 0, None).expect("the random sampler");
    let scene = builtin::cornell_box().expect("the built-in Cornell box");
    let params = frame_params(&scene, &scene.default_camera(), &RenderSettings::default(), sampler);
    let out = kernel::run_with(
        &ctx,
        &shader(FRAME_KERNEL),
        &input,
        &[&words(&params)],
        12 * normals.len(),
        normals.len() as u32,
    )
    .expect("the frame kernel");
    let v = Vec3::new(0.36, -0.48, 0.8);
    let (mut identical, mut total) = (0, 0);
    for (k, n) in normals.iter().enumerate() {
        let f = furnace_brdf::Frame::new(*n);
        let local = f.to_local(v);
        let want = [f.x, f.y, local, f.to_world(local)];
        for (j, (name, w)) in ["x", "y", "to_local", "to_world"].iter().zip(want).enumerate() {
            identical +=
                usize::from(close(&format!("normal {n:?}: {name}"), vec3_at(&out, 12 * k + 3 * j), w, 2e-6));
            total += 1;
        }
    }
    println!("frames: {identical} of {total} vectors bit-identical");
}

/// `frame_with_tangent` (the anisotropic BSDF's frame) against `Frame::with_tangent`: tangents
/// at random, near the normal (on both sides of the fallback's threshold), along it and zero
/// (the integrator's directions are unit or zero, never NaN). 2e-6: a few ULP of unit vectors, as for the plain frames, divided by the
/// tangent's part across the normal relative to its length (x is that part normalised, so the
/// rounding of the tangent's components grows by its inverse); a pair whose tangent sits at
/// the threshold may take either branch, and is only checked for a valid frame.
#[test]
fn frames_with_tangent_match_furnace_brdf() {
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(34);
    let mut pairs: Vec<(Vec3, Vec3)> = (0..20_000).map(|_| (rng.unit_vector(), rng.unit_vector())).collect();
    for k in 0..2_000 {
        let n = rng.unit_vector();
        let across = (rng.unit_vector() - n * n.dot(rng.unit_vector())).normalize_or(Vec3::X);
        // |across part|² / |t|² from 1e-9 to 1e-3 around the 1e-6 threshold.
        let e = 10f32.powf(-3.0 + 3.0 * (k as f32 / 2_000.0 - 0.5)) * rng.range(0.5, 2.0);
        pairs.push((n, 3.0 * (n + e * across)));
    }
    for n in [Vec3::Z, Vec3::NEG_Z, Vec3::new(0.6, 0.0, 0.8)] {
        pairs.extend([(n, n), (n, -2.0 * n), (n, Vec3::ZERO)]);
    }
    let input: Vec<u32> =
        pairs.iter().flat_map(|(n, t)| [n.to_array(), t.to_array()]).flatten().map(f32::to_bits).collect();
    let sampler = SamplerParams::new(SamplerKind::Random, 0, None).expect("the random sampler");
    let scene = builtin::cornell_box().expect("the built-in Cornell box");
    let params = frame_params(&scene, &scene.default_camera(), &RenderSettings::default(), sampler);
    let out = kernel::run_with(
        &ctx,
        &shader(TANGENT_FRAME_KERNEL),
        &input,
        &[&words(&params)],
        6 * pairs.len(),
        pairs.len() as u32,
    )
    .expect("the tangent frame kernel");
    let (mut identical, mut total, mut boundary) = (0, 0, 0);
    for (k, &(n, t)) in pairs.iter().enumerate() {
        let f = furnace_brdf::Frame::with_tangent(n, t);
        let across = t - n * n.dot(t);
        let ratio = across.length_squared() / t.length_squared();
        if (ratio / 1e-6 - 1.0).abs() < 1e-3 {
            // At the threshold: either frame, but a frame around n.
            let (x, y) = (vec3_at(&out, 6 * k), vec3_at(&out, 6 * k + 3));
            assert!(x.dot(n).abs() < 1e-5 && y.dot(n).abs() < 1e-5 && (x.cross(y) - n).length() < 1e-5);
            boundary += 1;
            continue;
        }
        let tol = if !(ratio >= 1e-6) { 2e-6 } else { 2e-6 / ratio.sqrt().min(1.0) };
        for (j, (name, w)) in ["x", "y"].iter().zip([f.x, f.y]).enumerate() {
            let what = format!("normal {n:?} tangent {t:?}: {name}");
            identical += usize::from(close(&what, vec3_at(&out, 6 * k + 3 * j), w, tol));
            total += 1;
        }
    }
    println!("tangent frames: {identical} of {total} vectors bit-identical, {boundary} at the threshold");
}

#[test]
fn russian_roulette_survival_matches() {
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(33);
    let mut throughputs: Vec<Vec3> = (0..10_000)
        .map(|_| {
            Vec3::new(rng.range(0.0, 2.0), rng.range(0.0, 2.0), rng.range(0.0, 2.0))
                * rng.pick(&[1e-6, 1e-2, 1.0, 10.0])
        })
        .collect();
    throughputs.extend([
        Vec3::ZERO,
        Vec3::ONE,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::splat(f32::MAX),
        Vec3::new(1e-40, 0.0, 0.0),
    ]);
    let input: Vec<u32> = throughputs.iter().flat_map(|t| t.to_array().map(f32::to_bits)).collect();
    let sampler = SamplerParams::new(SamplerKind::Random, 0, None).expect("the random sampler");
    let scene = builtin::cornell_box().expect("the built-in Cornell box");
    let params = frame_params(&scene, &scene.default_camera(), &RenderSettings::default(), sampler);
    let out = kernel::run_with(
        &ctx,
        &shader(ROULETTE_KERNEL),
        &input,
        &[&words(&params)],
        throughputs.len(),
        throughputs.len() as u32,
    )
    .expect("the roulette kernel");
    for (k, t) in throughputs.iter().enumerate() {
        let want = furnace_render::russian_roulette_survival(*t);
        let got = f32::from_bits(out[k]);
        // Exact, except that a GPU may flush the subnormal 1e-40 to zero.
        let flushed = want < f32::MIN_POSITIVE && got == 0.0;
        assert!(got == want || flushed, "throughput {t:?}: GPU {got:e} vs Rust {want:e}");
    }
}
