//! The error paths of furnace-gpu, provoked on purpose: a lost device, buffers over the
//! adapter's limits, and an allocation that fails.
//!
//! - **Device loss**: `wgpu::Device::destroy` loses the device the way a driver reset does
//!   (wgpu marks it invalid and calls the device-lost callback at its next poll). After it,
//!   every call must return `Err(GpuError::DeviceLost)` — the first and all later ones — within
//!   seconds, not panic or hang; each runs on its own thread with a time limit — reading the
//!   film and rendering a pass ([`rendering_on_a_lost_device_is_device_lost`]: it panicked in
//!   `wgpu::util::DeviceExt::create_buffer_init` until the renderer used
//!   `GpuContext::buffer_init`).
//! - **Too large**: the checks run before anything is allocated, so they are provoked at no
//!   cost: a film of one row more than the largest storage binding holds (any adapter), and a
//!   scene whose vertex buffer is 16 bytes over it (built in host memory, so only where the
//!   limit is at most 256 MiB, as the software adapter's 128 MiB; elsewhere that test prints that it is left
//!   out). The error must name the buffer and both sizes.
//! - **Out of memory**: exhausting real memory would take the machine's memory with it
//!   (a software adapter's device memory *is* host memory). Instead a child process (this test binary,
//!   running [`oom_child`]) opens the device, caps its own address space (`prlimit --as`, from
//!   util-linux) at what it uses plus 64 MiB, and creates a film as large as one binding allows
//!   (160 MiB on the software adapter): the driver's allocation fails at once, nothing is touched, and
//!   furnace-gpu must return `GpuError::Wgpu` saying "memory"; an 8×8 film allocated next must
//!   work. The same child without the cap (the control) allocates both. Linux only; on a
//!   hardware adapter the cap does not bound device memory, so the test prints that and passes.
//!
//! Like every GPU test, these fail without an adapter unless `FURNACE_SKIP_GPU_TESTS=1`.

use furnace_gpu::film::FilmPrecision;
use furnace_gpu::{GpuContext, GpuError, GpuRenderer};
use furnace_render::RenderSettings;
use furnace_scene::{Scene, builtin};
use furnace_tests::gpu::test_context;
use std::sync::mpsc;
use std::time::Duration;

/// Runs `f` on its own thread and returns its result; panics saying so if `f` panics or takes
/// longer than `limit` (a hang).
fn within<T: Send + 'static>(what: &str, limit: Duration, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(limit) {
        Ok(v) => v,
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what}: no answer within {limit:?} (a hang)"),
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("{what}: panicked (see above)"),
    }
}

/// How long one call on a lost device may take: answers come at once; a software adapter under a loaded
/// 2-core machine takes seconds for anything, so 60 s separates slow from hung.
const LIMIT: Duration = Duration::from_secs(60);

/// An 8×8 Cornell box renderer with one pass done and read back (the device works).
fn working_renderer(ctx: GpuContext) -> GpuRenderer {
    let scene = builtin::cornell_box().unwrap();
    let settings = RenderSettings { width: 8, height: 8, ..RenderSettings::default() };
    let mut r = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings).unwrap();
    r.render_pass(0, 1).unwrap();
    assert!(r.film().unwrap().counts().iter().all(|&c| c == 1));
    r
}

fn assert_lost<T: std::fmt::Debug>(what: &str, r: Result<T, GpuError>) {
    match r {
        Err(GpuError::DeviceLost(_)) => {}
        other => panic!("{what} on a destroyed device: expected Err(DeviceLost), got {other:?}"),
    }
}

#[test]
fn reading_a_lost_device_is_device_lost_every_time() {
    let Some(ctx) = test_context() else { return };
    let r = working_renderer(ctx);
    r.context().device.destroy();
    let mut r = within("film() after destroy", LIMIT, move || {
        assert_lost("film()", r.film());
        // A lost device stays lost: the same error again, not a validation error about
        // invalid buffers (the loss's consequences).
        assert_lost("film() again", r.film());
        assert_lost("check()", r.context().check());
        let buffer = r.context().buffer_init("after loss", &[1; 8], wgpu::BufferUsages::UNIFORM);
        assert_lost("buffer_init()", buffer);
        r
    });
    let zero = furnace_render::Film::new(8, 8);
    within("load_film() after destroy", LIMIT, move || assert_lost("load_film()", r.load_film(&zero)));
}

/// `GpuContext::buffer_init`, the lost-device-safe `create_buffer_init`, stores what it is
/// given (a length that is not a multiple of 4 is padded with zeros).
#[test]
fn buffer_init_holds_its_contents() {
    let Some(ctx) = test_context() else { return };
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    for (bytes, words) in [
        (&[1u8, 2, 3, 4, 5, 6, 7][..], &[0x0403_0201u32, 0x0007_0605][..]),
        (&[9, 8, 7, 6][..], &[0x0607_0809][..]),
        (&[][..], &[0][..]),
    ] {
        let buffer = ctx.buffer_init("test", bytes, usage).unwrap();
        assert_eq!(furnace_gpu::film::read_buffer(&ctx, &buffer).unwrap(), words, "{bytes:?}");
    }
}

/// `film::read_buffers` reads several buffers in one submission and gives each one's words, in
/// the order given, to its closure (a film's sums, counts, marks and AOVs are read this way).
#[test]
fn read_buffers_gives_each_buffers_words_in_order() {
    let Some(ctx) = test_context() else { return };
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let contents: [Vec<u32>; 3] = [(0..1000).collect(), vec![7], (0..64).map(|i| i * 3 + 1).collect()];
    let buffers: Vec<wgpu::Buffer> =
        contents.iter().map(|w| ctx.buffer_init("test", bytemuck::cast_slice(w), usage).unwrap()).collect();
    let read = furnace_gpu::film::read_buffers(&ctx, &buffers.iter().collect::<Vec<_>>(), |words| {
        words.iter().map(|w| w.to_vec()).collect::<Vec<_>>()
    })
    .unwrap();
    assert_eq!(read, contents);
}

/// Rendering on a lost device is `DeviceLost`. It failed (a panic) while `render_pass` made its
/// uniform buffer with `wgpu::util::DeviceExt::create_buffer_init`: on a lost device that
/// buffer cannot be mapped at creation ("Failed to get mapped range for buffer created with
/// mapped_at_creation"); the renderer now uses `GpuContext::buffer_init`.
#[test]
fn rendering_on_a_lost_device_is_device_lost() {
    // Loss not yet noticed (destroy, then render at once), and noticed (after a read).
    for noticed in [false, true] {
        let Some(ctx) = test_context() else { return };
        let mut r = working_renderer(ctx);
        r.context().device.destroy();
        if noticed {
            assert_lost("film()", r.film());
        }
        within(&format!("render_pass() after destroy (noticed: {noticed})"), LIMIT, move || {
            assert_lost("render_pass()", r.render_pass(1, 1));
            assert_lost("render_pass() again", r.render_pass(2, 1));
            assert_lost("film()", r.film());
        });
    }
}

/// Asserts a [`GpuError::TooLarge`] about `what_contains`, of `bytes` over `limit`, whose
/// message names the buffer and both sizes.
fn assert_too_large(r: Result<GpuRenderer, GpuError>, what_contains: &str, bytes: u64, limit: u64) {
    let e = r.map(|_| ()).expect_err("a renderer was built");
    let message = e.to_string();
    match &e {
        GpuError::TooLarge { what, bytes: b, limit: l } => {
            assert!(what.contains(what_contains), "{message}");
            assert_eq!((*b, *l), (bytes, limit), "{message}");
        }
        other => panic!("expected TooLarge about {what_contains}, got {other:?}"),
    }
    for part in [what_contains.to_string(), bytes.to_string(), limit.to_string()] {
        assert!(message.contains(&part), "'{part}' missing from: {message}");
    }
}

#[test]
fn a_film_over_the_binding_limit_is_too_large() {
    let Some(ctx) = test_context() else { return };
    let limit = ctx.max_storage_binding().min(ctx.device.limits().max_buffer_size);
    let per_pixel = FilmPrecision::for_context(&ctx).sum_bytes_per_pixel();
    // The smallest 4096-wide film over the limit (nothing is allocated: the check comes first).
    let width = 4096u32;
    let height = u32::try_from((limit / per_pixel + 1).div_ceil(u64::from(width))).unwrap();
    let bytes = u64::from(width) * u64::from(height) * per_pixel;
    assert!(bytes > limit && bytes - u64::from(width) * per_pixel <= limit);
    let scene = builtin::cornell_box().unwrap();
    let settings = RenderSettings { width, height, ..RenderSettings::default() };
    let r = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings);
    assert_too_large(r, &format!("a {width}×{height} film"), bytes, limit);
}

#[test]
fn a_scene_over_the_binding_limit_is_too_large() {
    let Some(ctx) = test_context() else { return };
    let limit = ctx.max_storage_binding().min(ctx.device.limits().max_buffer_size);
    if limit > 256 << 20 {
        eprintln!("binding limit {limit} bytes: a scene over it is too big to build here; left out");
        return;
    }
    // The Cornell box plus unused vertices up to one vertex (16 bytes on the GPU: position and
    // normal) more than the limit holds; their triangles are the box's, so the BVH is small.
    let mut scene: Scene = builtin::cornell_box().unwrap();
    let nv = limit / 16 + 1;
    let g = &mut scene.geometry;
    g.positions.resize(nv as usize, glam::Vec3::ZERO);
    g.normals.resize(nv as usize, g.normals[0]);
    let settings = RenderSettings { width: 8, height: 8, ..RenderSettings::default() };
    let r = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings);
    assert_too_large(r, &format!("the scene's vertex buffer ({nv} vertices)"), nv * 16, limit);
}

#[test]
fn device_memory_is_read_and_the_upload_weighed_against_it() {
    let Some(ctx) = test_context() else { return };
    if ctx.info.backend == wgpu::Backend::Vulkan {
        let m = ctx.memory().expect("a Vulkan device states its heaps");
        eprintln!("{}: {m:?}", ctx.describe());
        // Any Vulkan device has at least 64 MiB; the room cannot exceed the heap.
        assert!(m.heap >= 64 << 20 && m.available() > 0 && m.available() <= m.heap, "{m:?}");
    }
    let precision = FilmPrecision::for_context(&ctx);
    let scene = builtin::forest(4, 2);
    let settings = RenderSettings { width: 16, height: 8, ..RenderSettings::default() };
    let r = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings).unwrap();
    let parts = r.memory_parts().to_vec();
    let part = |name: &str| parts.iter().find(|(n, _)| *n == name).map(|p| p.1).expect(name);
    // Uploaded buffers are padded to at least 16 bytes each: 5 for the two-level BVH, 12 more for
    // the scene's geometry, materials, lights and environment.
    assert!(part("BVH").abs_diff(r.bvh_bytes()) <= 5 * 16, "{parts:?} against {}", r.bvh_bytes());
    let scene_parts = part("geometry and materials") + part("lights") + part("environment");
    assert!(scene_parts + 12 * 16 >= r.scene_bytes(), "{parts:?} against {}", r.scene_bytes());
    assert_eq!(part("film"), 16 * 8 * (precision.sum_bytes_per_pixel() + 8));
    // One byte less room than the render needs: refused, naming its largest part.
    let needed: u64 = parts.iter().map(|p| p.1).sum();
    let small = furnace_gpu::memory::DeviceMemory { heap: needed - 1, free: None };
    match furnace_gpu::memory::check_fits(&parts, small, "a small device") {
        Err(e @ GpuError::OutOfDeviceMemory { needed: n, .. }) => {
            assert_eq!(n, needed);
            assert!(e.to_string().contains("BVH"), "{e}");
        }
        other => panic!("expected OutOfDeviceMemory, got {other:?}"),
    }
}

/// What [`oom_child`] prints before its result.
const OOM_TAG: &str = "oom child: ";

/// Run by [`out_of_memory_is_an_error_not_a_crash`] in a child process: caps its own address
/// space (unless `FURNACE_OOM_CHILD=uncapped`, the control), allocates and clears a film as
/// large as one binding allows, then an 8×8 one, and prints `oom child: BIG | SMALL`.
#[test]
#[ignore = "run by out_of_memory_is_an_error_not_a_crash in a child process (it caps its own memory)"]
fn oom_child() {
    let Some(mode) = std::env::var_os("FURNACE_OOM_CHILD") else {
        eprintln!("run by out_of_memory_is_an_error_not_a_crash only (it caps its own address space)");
        return;
    };
    let ctx = test_context().expect("the parent checked FURNACE_SKIP_GPU_TESTS");
    if furnace_gpu::context::is_hardware(&ctx.info) {
        println!("{OOM_TAG}hardware adapter: an address-space cap does not bound device memory");
        return;
    }
    if mode != "uncapped" {
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let vm_kib: u64 = status
            .lines()
            .find_map(|l| l.strip_prefix("VmSize:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
            .expect("VmSize in /proc/self/status");
        let cap = (vm_kib << 10) + (64 << 20);
        let capped = std::process::Command::new("prlimit")
            .args(["--pid", &std::process::id().to_string(), &format!("--as={cap}")])
            .status()
            .expect("prlimit (util-linux) runs");
        assert!(capped.success(), "prlimit failed");
    }
    // As large as one binding allows (128 MiB of sums on the software adapter, plus 32 MiB of counts):
    // legal, but more than the 64 MiB of address space left under the cap.
    let precision = FilmPrecision::for_context(&ctx);
    let limit = ctx.max_storage_binding().min(ctx.device.limits().max_buffer_size);
    let pixels = limit / precision.sum_bytes_per_pixel();
    let film = |width: u32, height: u32| {
        furnace_gpu::film::GpuFilm::new(&ctx, width, height, precision)
            .and_then(|mut film| film.clear(&ctx).map(|()| film.width()))
    };
    let big = film(2048, u32::try_from(pixels / 2048).unwrap());
    let small = film(8, 8);
    println!("{OOM_TAG}{big:?} | {small:?}");
}

/// Runs [`oom_child`] in a child process with `FURNACE_OOM_CHILD=mode`; returns its result
/// line, asserting that it ended normally.
fn oom_child_says(mode: &str) -> String {
    // The test's name in this binary: its module path without the crate's name.
    let name = match module_path!().split_once("::") {
        Some((_, module)) => format!("{module}::oom_child"),
        None => "oom_child".to_string(),
    };
    let o = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", &name, "--ignored", "--nocapture", "--test-threads", "1"])
        .env("FURNACE_OOM_CHILD", mode)
        .output()
        .unwrap();
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let line = out.lines().find_map(|l| l.split_once(OOM_TAG).map(|(_, r)| r.to_string()));
    let line =
        line.unwrap_or_else(|| panic!("{mode} child ended without a result ({:?}):\n{out}\n{err}", o.status));
    assert!(o.status.success(), "{mode} child failed after '{line}' ({:?}):\n{out}\n{err}", o.status);
    line
}

#[cfg(target_os = "linux")]
#[test]
fn out_of_memory_is_an_error_not_a_crash() {
    if std::env::var("FURNACE_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        eprintln!("FURNACE_SKIP_GPU_TESTS=1: skipping a GPU test");
        return;
    }
    let control = oom_child_says("uncapped");
    if control.starts_with("hardware adapter") {
        eprintln!("{control}: out of memory not provoked");
        return;
    }
    // Without the cap both films are allocated: the failure below is the cap's doing.
    assert_eq!(control, "Ok(2048) | Ok(8)", "uncapped");
    let capped = oom_child_says("capped");
    let (big, small) = capped.split_once(" | ").unwrap();
    assert!(big.starts_with("Err(Wgpu(") && big.to_lowercase().contains("memory"), "{capped}");
    // An allocation that fails does not take the device with it: the next one works.
    assert_eq!(small, "Ok(8)", "{capped}");
}
