//! The display maths of `furnace-post` on the GPU: exposure, tone mapping, the exact sRGB OETF
//! and 8-bit quantisation, for a viewer that tone-maps the accumulating film every frame.
//!
//! [`TONEMAP_WGSL`] is a twin of `furnace-post` (`Tonemap::apply`, `linear_to_srgb`,
//! `quantize_unorm8`): same constants, same branches; `tests/display_parity.rs` runs both on
//! the same inputs. Its API:
//!
//! ```wgsl
//! fn post_display(linear: vec3<f32>, scale: f32, tonemap: u32) -> vec3<f32> // sRGB-encoded, in [0, 1]
//! fn post_quantize_unorm8(v: f32) -> u32                                    // quantize_unorm8
//! fn post_tonemap(c: vec3<f32>, tonemap: u32) -> vec3<f32>                  // Tonemap::apply
//! fn post_linear_to_srgb(x: f32) -> f32                                     // linear_to_srgb
//! fn post_sanitize(c: vec3<f32>) -> vec3<f32>         // NaN → 0, negatives → 0, +∞ → f32::MAX
//! fn post_aces_filmic(x: f32) -> f32                                        // aces_filmic
//! fn post_pbr_neutral(c: vec3<f32>) -> vec3<f32>                            // pbr_neutral
//! ```
//!
//! `post_display(linear, scale, tonemap)` with `scale = `[`furnace_post::exposure_scale`]`(ev)`
//! (formed on the host) and `tonemap = `[`tonemap_code`]`(t)` is
//! `furnace_post::Tonemap::apply(linear · scale)` then `linear_to_srgb` per channel: what
//! `furnace_post::pixel_to_srgb8` quantises. A fragment shader writes it to a non-sRGB 8-bit
//! target (`Rgba8Unorm`: the target's float → 8-bit conversion rounds to nearest on common
//! hardware, but Vulkan and D3D allow the other neighbour close to a half), or
//! `post_quantize_unorm8` turns it into exactly post's code. Not to an `…Srgb` target: that
//! would encode twice.
//!
//! The module needs the `TONEMAP_*` constants before it, generated from the Rust ones below by
//! [`consts_wgsl`]; [`wgsl`] is both, ready to compose. It declares no bindings.
//!
//! ```
//! use furnace_gpu::display;
//! let src = furnace_gpu::wgsl::compose(&[
//!     &display::wgsl(),
//!     "@group(0) @binding(0) var film: texture_2d<f32>;", // the viewer's own bindings and entry points
//! ]);
//! assert!(src.contains("const TONEMAP_ACES: u32 = 0u;") && src.contains("fn post_display("));
//! assert_eq!(display::tonemap_code(furnace_post::Tonemap::PbrNeutral), display::TONEMAP_PBR_NEUTRAL);
//! ```
//!
//! How close the GPU comes: WGSL's `pow` (exp2(y·log2 x)) and `/` are not correctly rounded, so
//! the float results agree within a few 10⁻⁷ (up to ~2·10⁻⁶ in PBR Neutral's dark desaturated
//! channels, where 1 − 1/(…) cancels and the sRGB slope is 12.92), and the 8-bit codes agree
//! except where the exact value lies that close to a rounding boundary (`tests/display_parity.rs`
//! states the tolerances and the measured values). NaN, ±∞ and negative input give exactly
//! post's outputs; `post_quantize_unorm8` is post's `quantize_unorm8` bit for bit.

use crate::shared::{Binding, BindingKind, BindingTable, WgslType, wgsl_struct};
use crate::{GpuContext, GpuError};
use furnace_post::Tonemap;
use glam::Vec3;

/// The WGSL twin of `furnace-post`'s display maths (see the module documentation). Needs
/// [`consts_wgsl`] before it ([`wgsl`] composes both).
pub const TONEMAP_WGSL: &str = include_str!("wgsl/tonemap.wgsl");

crate::wgsl_consts! {
    /// The WGSL `const` declarations of the tone map codes below (`TONEMAP_ACES`, …), which
    /// [`TONEMAP_WGSL`] needs before it.
    fn consts_wgsl;
    /// The `tonemap` code of [`Tonemap::Aces`].
    pub const TONEMAP_ACES: u32 = 0;
    /// The `tonemap` code of [`Tonemap::PbrNeutral`].
    pub const TONEMAP_PBR_NEUTRAL: u32 = 1;
    /// The `tonemap` code of [`Tonemap::Clamp`] (any unknown code clamps too).
    pub const TONEMAP_CLAMP: u32 = 2;
}

/// The WGSL `tonemap` code of a tone map (the `TONEMAP_*` constants).
pub fn tonemap_code(t: Tonemap) -> u32 {
    match t {
        Tonemap::Aces => TONEMAP_ACES,
        Tonemap::PbrNeutral => TONEMAP_PBR_NEUTRAL,
        Tonemap::Clamp => TONEMAP_CLAMP,
    }
}

/// The whole module, ready to compose into a shader: [`consts_wgsl`] then [`TONEMAP_WGSL`].
pub fn wgsl() -> String {
    consts_wgsl() + TONEMAP_WGSL
}

crate::gpu_struct! {
    /// The uniform block of [`display_on_gpu`]'s kernel (16 bytes); its WGSL declaration is
    /// generated from this one.
    pub struct DisplayParams {
        /// The exposure scale, `furnace_post::exposure_scale(ev)`.
        pub scale: f32 => WgslType::F32,
        /// [`tonemap_code`] of the tone map.
        pub tonemap: u32 => WgslType::U32,
        /// The number of colours.
        pub count: u32 => WgslType::U32,
        /// Rust-only padding to 16 bytes (a uniform block's size is a multiple of 16).
        pub pad: u32 => WgslType::PAD,
    }
}

const _: () = assert!(size_of::<DisplayParams>() == 16);

/// Workgroup size of [`display_on_gpu`]'s kernel.
const GROUP: u32 = 64;
/// Workgroups along x per row of its 2-D dispatch (WebGPU guarantees 65535 per dimension).
const ROW: u32 = 65_535;

/// The kernel's bindings: the colours in (3 `f32` each, packed: `array<f32>`, not the 16-byte
/// `vec3<f32>`), the display values out, the parameters.
fn binding_table() -> BindingTable {
    BindingTable::new(
        0,
        0,
        vec![
            Binding::read("display_in", "array<f32>"),
            Binding::read_write("display_out", "array<f32>"),
            Binding {
                name: "display_params",
                ty: "DisplayParams".into(),
                kind: BindingKind::Uniform { dynamic: false, min_size: size_of::<DisplayParams>() as u64 },
            },
        ],
    )
}

/// The WGSL of [`display_on_gpu`]'s kernel: [`wgsl`], the parameters and bindings, and a
/// `main` that runs `post_display` on each colour.
pub fn kernel_source() -> String {
    crate::wgsl::compose(&[
        &wgsl(),
        &wgsl_struct::<DisplayParams>(true),
        &binding_table().wgsl(),
        &format!(
            r#"
// One colour per invocation of a 2-D dispatch of {GROUP}-wide workgroups, rows of `groups.x`.
@compute @workgroup_size({GROUP})
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {{
    let i = gid.x + gid.y * groups.x * {GROUP}u;
    if i >= display_params.count {{
        return;
    }}
    let c = vec3<f32>(display_in[3u * i], display_in[3u * i + 1u], display_in[3u * i + 2u]);
    let v = post_display(c, display_params.scale, display_params.tonemap);
    display_out[3u * i] = v.x;
    display_out[3u * i + 1u] = v.y;
    display_out[3u * i + 2u] = v.z;
}}
"#
        ),
    ])
}

/// `post_display` of each colour on the GPU: exposure `2^ev` ([`furnace_post::exposure_scale`],
/// on the host), `tonemap`, the sRGB OETF; sRGB-encoded values in [0, 1] before quantisation,
/// the GPU's twin of `furnace_post::pixel_to_srgb8` without its last step. For tests and tools:
/// a pipeline is built on each call.
///
/// # Errors
/// [`GpuError::TooLarge`] when the colours exceed the adapter's storage binding limit; a
/// device error (validation, lost device) from building or running the kernel.
pub fn display_on_gpu(
    ctx: &GpuContext,
    linear: &[Vec3],
    ev: f32,
    tonemap: Tonemap,
) -> Result<Vec<[f32; 3]>, GpuError> {
    if linear.is_empty() {
        return Ok(Vec::new());
    }
    let bytes = 12 * linear.len() as u64;
    let limit = ctx.upload_limit();
    let count = u32::try_from(linear.len()).ok().filter(|_| bytes <= limit).ok_or_else(|| {
        GpuError::TooLarge { what: format!("{} colours to display", linear.len()), bytes, limit }
    })?;
    let table = binding_table();
    let device = &ctx.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("display"),
        entries: &table.layout_entries(),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("display"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("display"),
        source: wgpu::ShaderSource::Wgsl(kernel_source().into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("display"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Wgpu(e.to_string()));
    }
    let input: Vec<f32> = linear.iter().flat_map(|c| c.to_array()).collect();
    let input = ctx.buffer_init("display in", bytemuck::cast_slice(&input), wgpu::BufferUsages::STORAGE)?;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("display out"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let params = DisplayParams {
        scale: furnace_post::exposure_scale(ev),
        tonemap: tonemap_code(tonemap),
        count,
        pad: 0,
    };
    let params =
        ctx.buffer_init("display params", bytemuck::bytes_of(&params), wgpu::BufferUsages::UNIFORM)?;
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("display"),
        layout: &layout,
        entries: &table.bind_entries(vec![
            input.as_entire_binding(),
            output.as_entire_binding(),
            params.as_entire_binding(),
        ]),
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        let groups = count.div_ceil(GROUP);
        let (x, y) = if groups <= ROW { (groups, 1) } else { (ROW, groups.div_ceil(ROW)) };
        pass.dispatch_workgroups(x, y, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let words = crate::film::read_buffer(ctx, &output)?;
    Ok(words
        .chunks_exact(3)
        .take(linear.len())
        .map(|w| [f32::from_bits(w[0]), f32::from_bits(w[1]), f32::from_bits(w[2])])
        .collect())
}
