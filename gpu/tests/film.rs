//! [`GpuFilm`]: 10⁶ frames without drift in both precisions; non-finite samples rejected and
//! counted; write → read round trips (resume).
//!
//! The samples are made from integer hashes by perturbing the mantissa of 0.1f32, so the GPU and
//! the CPU see bit-identical inputs and the CPU can form the exact mean in `f64`.

use furnace_gpu::GpuContext;
use furnace_gpu::film::{FilmPrecision, GpuFilm, uniform};
use furnace_render::Film;
use furnace_tests::gpu::test_context;

const FRAMES: u32 = 1_000_000;
const PIXELS: u32 = 64;
/// Every this many frames pixel 0 gets a NaN and pixel 1 an infinity.
const BAD_EVERY: u32 = 100_000;

/// lowbias32 (Chris Wellons), identical in the WGSL below.
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// 0.1f32 with its mantissa moved by up to ±2¹⁵ ulp (values in 0.1 ± 2.4e-4).
fn value(frame: u32, channel: u32) -> f32 {
    let h = hash(frame.wrapping_mul(0x9e37_79b9) ^ hash(channel));
    f32::from_bits((0x3dcc_cccd_u32 + (h & 0xffff)).wrapping_sub(0x8000))
}

const SHADER: &str = r#"
@group(0) @binding(2) var<uniform> params: vec4<u32>; // x: pixels, y: frames, z: bad every, w: first frame

fn hash(x0: u32) -> u32 {
    var x = x0;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    return x ^ (x >> 16u);
}

fn value(frame: u32, channel: u32) -> f32 {
    let h = hash((frame * 0x9e3779b9u) ^ hash(channel));
    return bitcast<f32>((0x3dcccccdu + (h & 0xffffu)) - 0x8000u);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.x;
    if p >= params.x { return; }
    for (var f = params.w; f < params.w + params.y; f++) {
        var v = vec3<f32>(value(f, 3u * p), value(f, 3u * p + 1u), value(f, 3u * p + 2u));
        if f % params.z == params.z - 1u && p < 2u {
            // NaN (pixel 0) or +inf (pixel 1) in the green channel, built from bits.
            v.y = bitcast<f32>(select(0x7f800000u, 0x7fc00000u, p == 0u));
        }
        film_add(p, v);
    }
}
"#;

/// The thesis's running mean `(N·prev + new)/(N + 1)` in `f32`, kept in the sum slot of an
/// `F32Pass` film that is never folded, so that reading it back gives the mean.
const NAIVE: &str = r#"
fn film_add(pixel: u32, value: vec3<f32>) {
    let e = bitcast<vec3<u32>>(value) & vec3<u32>(0x7f800000u);
    if any(e == vec3<u32>(0x7f800000u)) { film_count[pixel].y += 1u; return; }
    let n = f32(film_count[pixel].x);
    film_sum[pixel] = vec4<f32>((n * film_sum[pixel].xyz + value) / (n + 1.0), 0.0);
    film_count[pixel].x += 1u;
}
"#;

fn accumulate(ctx: &GpuContext, precision: FilmPrecision, module: &str, fold: bool) -> Film {
    let mut film = GpuFilm::new(ctx, PIXELS, 1, precision).unwrap();
    let source = format!("{}{}{}", precision.bindings(0, 0), module, SHADER);
    let d = &ctx.device;
    let shader = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let [a, b]: [_; 2] = GpuFilm::layout_entries(0).try_into().unwrap();
    let u = wgpu::BindGroupLayoutEntry {
        binding: 2,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let bgl =
        d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &[a, b, u] });
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: Some(&pl),
        module: &shader,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    // Passes of PASS frames, one dispatch each, as a progressive render does them (an F32Pass
    // film is folded after each). Also keeps each invocation far below llvmpipe's limit of
    // 65535 loop iterations per invocation, past which the software adapter silently ends loops.
    const PASS: u32 = 1000;
    for k in 0..FRAMES.div_ceil(PASS) {
        let params = uniform(ctx, &[PIXELS, PASS.min(FRAMES - k * PASS), BAD_EVERY, k * PASS]);
        let [ea, eb]: [_; 2] = film.bind_entries(0).try_into().unwrap();
        let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &bgl,
            entries: &[ea, eb, wgpu::BindGroupEntry { binding: 2, resource: params.as_entire_binding() }],
        });
        let mut enc = d.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(PIXELS.div_ceil(64), 1, 1);
        }
        ctx.queue.submit([enc.finish()]);
        if fold {
            film.fold(ctx).unwrap();
        }
    }
    ctx.wait().unwrap();
    film.read(ctx).unwrap()
}

/// The exact mean of what each pixel accepted, and how many it accepted.
fn exact() -> Vec<([f64; 3], u64)> {
    (0..PIXELS)
        .map(|p| {
            let mut s = [0.0f64; 3];
            let mut n = 0u64;
            for f in 0..FRAMES {
                let bad = f % BAD_EVERY == BAD_EVERY - 1 && p < 2;
                if bad {
                    continue;
                }
                for (k, sk) in s.iter_mut().enumerate() {
                    *sk += f64::from(value(f, 3 * p + k as u32));
                }
                n += 1;
            }
            (s.map(|x| x / n as f64), n)
        })
        .collect()
}

/// Worst relative error of the film's means against the exact ones.
fn worst(data: &Film, exact: &[([f64; 3], u64)], mean_is_stored: bool) -> f64 {
    let mut worst = 0.0f64;
    for (i, (m, n)) in exact.iter().enumerate() {
        assert_eq!(data.counts()[i], *n, "pixel {i}: accepted count");
        let got = if mean_is_stored { data.sums()[i] } else { data.mean(i) };
        for k in 0..3 {
            worst = worst.max(((got[k] - m[k]) / m[k]).abs());
        }
    }
    worst
}

/// 10⁶ frames into 64 pixels, both precisions: relative error below 1e-5 (the brief's bound);
/// f64 sums err by ≤ n·2⁻⁵³ ≈ 1e-10, compensated f32 by ≈ 2·2⁻²⁴ ≈ 1.2e-7. The thesis's f32
/// Measured on the software adapter: f64 0 (bit-identical to the CPU's f64 sum, same order), compensated
/// 2.9e-7, thesis running mean 9.3e-3. The thesis's f32
/// running mean must exceed the bound (it drifted visibly after ~2000 frames), which shows the
/// test can fail.
#[test]
fn million_frames_do_not_drift() {
    let Some(ctx) = test_context() else { return };
    let exact = exact();
    let expected_rejected = 2 * u64::from(FRAMES / BAD_EVERY);
    let mut precisions = vec![FilmPrecision::F32Pass];
    if ctx.shader_f64 {
        precisions.push(FilmPrecision::F64);
    } else {
        eprintln!("{}: no SHADER_F64; testing the F32Pass film only", ctx.describe());
    }
    let mut failures = Vec::new();
    for precision in precisions {
        let data = accumulate(&ctx, precision, &precision.wgsl(), true);
        let w = worst(&data, &exact, false);
        eprintln!("{precision:?}: worst relative error of the mean after {FRAMES} frames: {w:.3e}");
        if !(w < 1e-5) {
            failures.push(format!("{precision:?} drifted: {w:e}"));
        }
        assert_eq!(data.rejected(), expected_rejected, "{precision:?}: rejected samples");
    }
    assert!(failures.is_empty(), "{} on {}", failures.join("; "), ctx.describe());
    let naive = accumulate(&ctx, FilmPrecision::F32Pass, NAIVE, false);
    let w = worst(&naive, &exact, true);
    eprintln!("thesis f32 running mean: worst relative error {w:.3e}");
    assert!(w > 1e-5, "the naive running mean should drift past 1e-5 (got {w:e}): the test lost its teeth");
}

/// What is written (to resume) reads back exactly, in both precisions.
#[test]
fn write_then_read_round_trips() {
    let Some(ctx) = test_context() else { return };
    let (w, h) = (7, 5);
    let data = Film::from_parts(
        w,
        h,
        (0..w * h).map(|i| glam::DVec3::new(f64::from(i) / 3.0, 1e7 + f64::from(i) * 1e-3, 0.1)).collect(),
        (0..u64::from(w * h)).map(|i| i * 1000 + 1).collect(),
        42,
    )
    .unwrap();
    for precision in [FilmPrecision::F64, FilmPrecision::F32Pass] {
        if precision == FilmPrecision::F64 && !ctx.shader_f64 {
            continue;
        }
        let mut film = GpuFilm::new(&ctx, w, h, precision).unwrap();
        film.write(&ctx, &data).unwrap();
        let back = film.read(&ctx).unwrap();
        assert_eq!((back.counts(), back.rejected()), (data.counts(), data.rejected()));
        assert_eq!(back.sums(), data.sums(), "{precision:?}");
        film.clear(&ctx).unwrap();
        let zero = film.read(&ctx).unwrap();
        assert!(zero.counts().iter().all(|&c| c == 0) && zero.rejected() == 0);
    }
}
