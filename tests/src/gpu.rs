//! GPU test contexts, and small compute kernels over `u32` buffers: how the parity tests run
//! WGSL twins on inputs the Rust side also sees.
//!
//! A kernel is WGSL that starts with [`PREAMBLE`] (the bindings and [`PREAMBLE`]'s
//! `invocation_index`) and has an entry point `@compute @workgroup_size(64) fn main(...)`.
//! Floats travel as bit patterns (`bitcast<f32>` / `f32::to_bits`).

use furnace_gpu::{AdapterChoice, GpuContext, GpuError};
use wgpu::util::DeviceExt;

/// The context a GPU test runs on: [`AdapterChoice::Best`].
///
/// Returns `None` (the test should return early and pass) only when the environment variable
/// `FURNACE_SKIP_GPU_TESTS=1` is set; it prints that it skipped. Otherwise a missing adapter
/// **panics** with the reason, so that CI, which installs lavapipe, fails rather than silently
/// skipping the GPU tests.
pub fn test_context() -> Option<GpuContext> {
    if std::env::var("FURNACE_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        eprintln!("FURNACE_SKIP_GPU_TESTS=1: skipping a GPU test");
        return None;
    }
    match GpuContext::new(&AdapterChoice::Best) {
        Ok(ctx) => Some(ctx),
        Err(e) => panic!(
            "GPU test needs an adapter: {e}. Install Mesa's lavapipe (apt-get install mesa-vulkan-drivers) \
             or set FURNACE_SKIP_GPU_TESTS=1 to skip GPU tests on purpose"
        ),
    }
}

/// Bindings every kernel uses, and the flat invocation index of a 2-D dispatch.
///
/// ```wgsl
/// @group(0) @binding(0) var<storage, read> input: array<u32>;
/// @group(0) @binding(1) var<storage, read_write> output: array<u32>;
/// @group(0) @binding(2) var<uniform> params: vec4<u32>; // x: invocation count
/// ```
pub const PREAMBLE: &str = r#"
@group(0) @binding(0) var<storage, read> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@group(0) @binding(2) var<uniform> params: vec4<u32>;

// Flat index of an invocation of a 2-D dispatch of 64-wide workgroups; compare with
// params.x (the invocation count) before using it.
fn invocation_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}
"#;

/// A kernel over the WGSL BSDFs: [`PREAMBLE`], the sampling module, the brdf module's generated
/// declarations and the module itself with every feature composed (the isotropic and the
/// anisotropic GGX, the thin film), then `body`.
pub fn brdf_kernel(body: &str) -> String {
    use furnace_gpu::wgsl;
    wgsl::compose(&[
        PREAMBLE,
        wgsl::SAMPLING,
        &furnace_gpu::brdf::declarations(),
        &wgsl::select(wgsl::BRDF, |_| true),
        body,
    ])
}

/// Workgroups along x per row of a 2-D dispatch (WebGPU guarantees 65535).
const ROW: u32 = 65_535;

/// Runs kernel `source` (which must contain [`PREAMBLE`]) for `invocations` invocations with
/// `input` bound read-only and an `output_words`-long zeroed output, and returns the output.
pub fn run(
    ctx: &GpuContext,
    source: &str,
    input: &[u32],
    output_words: usize,
    invocations: u32,
) -> Result<Vec<u32>, GpuError> {
    run_with(ctx, source, input, &[], output_words, invocations)
}

/// [`run`] with extra read-only storage buffers (tables, BVH nodes, triangles) bound at
/// `@group(0) @binding(3)`, `@binding(4)`, … in order; the kernel declares them itself, e.g.
/// `@group(0) @binding(3) var<storage, read> nodes: array<Node>;` (their bytes are the `u32`
/// words given here).
pub fn run_with(
    ctx: &GpuContext,
    source: &str,
    input: &[u32],
    extra: &[&[u32]],
    output_words: usize,
    invocations: u32,
) -> Result<Vec<u32>, GpuError> {
    let device = &ctx.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    // An explicit layout, so that a kernel may leave bindings unused.
    let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    let mut layout_entries = vec![
        entry(0, wgpu::BufferBindingType::Storage { read_only: true }),
        entry(1, wgpu::BufferBindingType::Storage { read_only: false }),
        entry(2, wgpu::BufferBindingType::Uniform),
    ];
    for k in 0..extra.len() as u32 {
        layout_entries.push(entry(3 + k, wgpu::BufferBindingType::Storage { read_only: true }));
    }
    let bind_layout = device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &layout_entries });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&bind_layout)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("kernel"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("kernel"),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Wgpu(e.to_string()));
    }
    let storage = |words: &[u32], usage| {
        // Zero-sized bindings are invalid: pad to at least 4 words.
        let mut v = words.to_vec();
        v.resize(v.len().max(4), 0);
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(&v),
            usage,
        })
    };
    let input_buf = storage(input, wgpu::BufferUsages::STORAGE);
    let extra_bufs: Vec<wgpu::Buffer> =
        extra.iter().map(|w| storage(w, wgpu::BufferUsages::STORAGE)).collect();
    let out_len = output_words.max(4);
    let bytes = (out_len * 4) as u64;
    if bytes > ctx.max_storage_binding() {
        return Err(GpuError::TooLarge {
            what: "kernel output".into(),
            bytes,
            limit: ctx.max_storage_binding(),
        });
    }
    let output_buf = storage(&vec![0; out_len], wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&[invocations, 0, 0, 0]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let mut entries = vec![
        wgpu::BindGroupEntry { binding: 0, resource: input_buf.as_entire_binding() },
        wgpu::BindGroupEntry { binding: 1, resource: output_buf.as_entire_binding() },
        wgpu::BindGroupEntry { binding: 2, resource: params.as_entire_binding() },
    ];
    for (k, b) in extra_bufs.iter().enumerate() {
        entries.push(wgpu::BindGroupEntry { binding: 3 + k as u32, resource: b.as_entire_binding() });
    }
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &bind_layout,
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        let groups = invocations.div_ceil(64).max(1);
        let (x, y) = if groups <= ROW { (groups, 1) } else { (ROW, groups.div_ceil(ROW)) };
        pass.dispatch_workgroups(x, y, 1);
    }
    encoder.copy_buffer_to_buffer(&output_buf, 0, &readback, 0, bytes);
    ctx.queue.submit([encoder.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Wgpu(e.to_string()));
    }
    readback.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    ctx.wait()?;
    let data = readback.slice(..).get_mapped_range().map_err(|e| GpuError::Wgpu(e.to_string()))?;
    let mut out: Vec<u32> = bytemuck::cast_slice(&data).to_vec();
    drop(data);
    readback.unmap();
    out.truncate(output_words);
    Ok(out)
}
