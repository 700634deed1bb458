//! A film on screen, without reading it back: [`FilmPresenter`] draws a [`GpuFilm`]'s means
//! into any render target (a window's surface, an offscreen texture), exposed, tone-mapped and
//! sRGB-encoded on the GPU by the maths of `furnace-post` (`tonemap.wgsl`, its twin;
//! `tests/display_parity.rs`); [`NoiseEstimator`] reduces the film's per-pixel variances to one
//! number, read back as a few kilobytes.
//!
//! ```no_run
//! # fn demo(gpu: &mut furnace_gpu::GpuRenderer, target: &wgpu::TextureView) -> Result<(), furnace_gpu::GpuError> {
//! use furnace_gpu::present::{FilmPresenter, Placement};
//! gpu.enable_display()?;
//! let presenter = FilmPresenter::new(gpu.context(), gpu.film_precision(), wgpu::TextureFormat::Bgra8Unorm)?;
//! let film = gpu.gpu_film();
//! let placement = Placement::fit((film.width(), film.height()), (1280, 720));
//! let ctx = gpu.context();
//! let mut encoder = ctx.device.create_command_encoder(&Default::default());
//! {
//!     let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
//!         color_attachments: &[Some(wgpu::RenderPassColorAttachment {
//!             view: target,
//!             depth_slice: None,
//!             resolve_target: None,
//!             ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
//!         })],
//!         ..Default::default()
//!     });
//!     presenter.draw(ctx, &mut pass, film, &placement, 0.0, furnace_post::Tonemap::Aces)?;
//! }
//! ctx.queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```

use crate::display::tonemap_code;
use crate::film::{DisplaySource, FilmPrecision, GpuFilm};
use crate::shared::{Binding, BindingKind, BindingTable, GpuStruct, WgslType, wgsl_struct};
use crate::{GpuContext, GpuError};
use furnace_post::{Tonemap, exposure_scale};

crate::gpu_struct! {
    /// The uniform block of [`FilmPresenter`]'s shader (48 bytes).
    pub struct PresentParams {
        /// The film's width in pixels.
        pub film_width: u32 => WgslType::U32,
        /// The film's height in pixels.
        pub film_height: u32 => WgslType::U32,
        /// Target pixel (x) where the film's left edge lies.
        pub origin_x: f32 => WgslType::F32,
        /// Target pixel (y) where the film's top edge lies.
        pub origin_y: f32 => WgslType::F32,
        /// Film pixels per target pixel.
        pub step: f32 => WgslType::F32,
        /// `2^EV`, the exposure scale (`furnace_post::exposure_scale`).
        pub exposure_scale: f32 => WgslType::F32,
        /// The tone map's code (`furnace_gpu::display::tonemap_code`).
        pub tonemap: u32 => WgslType::U32,
        /// 1 when the target's format encodes sRGB itself (the shader then writes linear values).
        pub target_srgb: u32 => WgslType::U32,
        /// The colour around the film (as written to the target).
        pub background: [f32; 4] => WgslType::VEC4_F32,
    }
}

/// Where a film lies in a target: the target pixel of its top-left corner and film pixels per
/// target pixel (nearest-pixel lookup).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Target pixel of the film's top-left corner (may be negative: the film is cropped).
    pub origin: [f32; 2],
    /// Film pixels per target pixel (1: one to one; 2: the film shown at half size).
    pub step: f32,
}

impl Placement {
    /// The film centred in the target, one to one when it fits, else shrunk to fit (whole
    /// target pixels for the origin, so that one-to-one pixels are not resampled).
    pub fn fit(film: (u32, u32), target: (u32, u32)) -> Self {
        let (fw, fh) = (film.0.max(1) as f32, film.1.max(1) as f32);
        let (tw, th) = (target.0.max(1) as f32, target.1.max(1) as f32);
        let step = (fw / tw).max(fh / th).max(1.0);
        let origin = [((tw - fw / step) * 0.5).floor(), ((th - fh / step) * 0.5).floor()];
        Self { origin, step }
    }

    /// The film pixel under target pixel `(x, y)` (its centre), if any.
    pub fn film_pixel(&self, film: (u32, u32), x: u32, y: u32) -> Option<(u32, u32)> {
        let fx = (x as f32 + 0.5 - self.origin[0]) * self.step;
        let fy = (y as f32 + 0.5 - self.origin[1]) * self.step;
        (fx >= 0.0 && fy >= 0.0 && fx < film.0 as f32 && fy < film.1 as f32).then_some((fx as u32, fy as u32))
    }
}

/// The colour drawn around the film: a dark grey, so that the film's black edge is visible.
pub const BACKGROUND: [f32; 4] = [0.08, 0.08, 0.08, 1.0];

/// The presenter's bindings: its uniform, then the film's buffers for `precision`.
fn binding_table(precision: FilmPrecision) -> BindingTable {
    let mut v = vec![Binding {
        name: "present",
        ty: PresentParams::NAME.to_string(),
        kind: BindingKind::Uniform { dynamic: false, min_size: size_of::<PresentParams>() as u64 },
    }];
    match precision {
        FilmPrecision::F64 => {
            v.push(Binding::read("film_sum", "array<vec4<f64>>"));
            v.push(Binding::read("film_count", "array<vec2<u32>>"));
        }
        FilmPrecision::F32Pass => v.push(Binding::read("film_means", "array<vec4<f32>>")),
    }
    BindingTable::new(0, 0, v)
}

/// The film's buffers, in [`binding_table`]'s order after the uniform.
fn film_resources(film: &GpuFilm) -> Result<Vec<wgpu::BindingResource<'_>>, GpuError> {
    match film.display_source() {
        Some(DisplaySource::F64 { sum, count }) => Ok(vec![sum.as_entire_binding(), count.as_entire_binding()]),
        Some(DisplaySource::F32 { means }) => Ok(vec![means.as_entire_binding()]),
        None => Err(GpuError::Unsupported(
            "the film has no display buffer: call GpuRenderer::enable_display (or GpuFilm::enable_display) first"
                .into(),
        )),
    }
}

/// The composed WGSL of the presenter for a film precision (for tests and tools).
pub fn shader_source(precision: FilmPrecision) -> String {
    let mean = match precision {
        FilmPrecision::F64 => include_str!("wgsl/present_f64.wgsl"),
        FilmPrecision::F32Pass => include_str!("wgsl/present_f32.wgsl"),
    };
    crate::wgsl::compose(&[
        &crate::display::wgsl(),
        &wgsl_struct::<PresentParams>(true),
        &binding_table(precision).wgsl(),
        mean,
        include_str!("wgsl/present.wgsl"),
    ])
}

/// Draws a [`GpuFilm`] into render passes of one target format.
#[derive(Debug)]
pub struct FilmPresenter {
    precision: FilmPrecision,
    format: wgpu::TextureFormat,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
}

impl FilmPresenter {
    /// A presenter of films of `precision` into targets of `format`.
    ///
    /// # Errors
    /// A shader or pipeline error.
    pub fn new(
        ctx: &GpuContext,
        precision: FilmPrecision,
        format: wgpu::TextureFormat,
    ) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let entries: Vec<_> = binding_table(precision)
            .layout_entries()
            .into_iter()
            .map(|e| wgpu::BindGroupLayoutEntry { visibility: wgpu::ShaderStages::FRAGMENT, ..e })
            .collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("present"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("present"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("present"),
            source: wgpu::ShaderSource::Wgsl(shader_source(precision).into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("present"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            multiview_mask: None,
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("present params"),
            size: size_of::<PresentParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Wgpu(e.to_string()));
        }
        Ok(Self { precision, format, layout, pipeline, params })
    }

    /// The target format it draws into.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// Records the film's draw into `pass` (a pass on a target of [`FilmPresenter::format`]):
    /// every target pixel is written (the film, or [`BACKGROUND`] around it). The uniform is
    /// written through the queue, so submit the pass before the next `draw`.
    ///
    /// # Errors
    /// [`GpuError::Unsupported`] for a film of another precision or without a display buffer.
    pub fn draw(
        &self,
        ctx: &GpuContext,
        pass: &mut wgpu::RenderPass<'_>,
        film: &GpuFilm,
        placement: &Placement,
        exposure_ev: f32,
        tonemap: Tonemap,
    ) -> Result<(), GpuError> {
        if film.precision() != self.precision {
            return Err(GpuError::Unsupported(format!(
                "a presenter of {:?} films cannot draw a {:?} film",
                self.precision,
                film.precision()
            )));
        }
        let srgb = self.format.is_srgb();
        // The background is given as display (sRGB-encoded) values; an sRGB target encodes.
        let background = if srgb {
            let b = BACKGROUND;
            [
                furnace_post::srgb_to_linear(b[0]),
                furnace_post::srgb_to_linear(b[1]),
                furnace_post::srgb_to_linear(b[2]),
                b[3],
            ]
        } else {
            BACKGROUND
        };
        let params = PresentParams {
            film_width: film.width(),
            film_height: film.height(),
            origin_x: placement.origin[0],
            origin_y: placement.origin[1],
            step: placement.step,
            exposure_scale: exposure_scale(exposure_ev),
            tonemap: tonemap_code(tonemap),
            target_srgb: u32::from(srgb),
            background,
        };
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let mut resources = vec![self.params.as_entire_binding()];
        resources.extend(film_resources(film)?);
        let entries = binding_table(self.precision).bind_entries(resources);
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("present"),
            layout: &self.layout,
            entries: &entries,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Draws the film into a new `width × height` texture of the presenter's format and reads it
    /// back, row-major RGBA (BGRA formats swizzled to RGBA): what a window of that size shows.
    /// For tests and screenshots; the format must be a 4-byte 8-bit one.
    ///
    /// # Errors
    /// As [`FilmPresenter::draw`], [`GpuError::Unsupported`] for another format, or a device error.
    pub fn render_to_rgba8(
        &self,
        ctx: &GpuContext,
        film: &GpuFilm,
        placement: &Placement,
        exposure_ev: f32,
        tonemap: Tonemap,
        size: (u32, u32),
    ) -> Result<Vec<[u8; 4]>, GpuError> {
        use wgpu::TextureFormat as F;
        let bgra = match self.format {
            F::Rgba8Unorm | F::Rgba8UnormSrgb => false,
            F::Bgra8Unorm | F::Bgra8UnormSrgb => true,
            f => {
                return Err(GpuError::Unsupported(format!(
                    "render_to_rgba8 reads 8-bit RGBA/BGRA, not {f:?}"
                )));
            }
        };
        let (w, h) = (size.0.max(1), size.1.max(1));
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("present target"),
            size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let row_bytes =
            (4 * w).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("present readback"),
            size: u64::from(row_bytes) * u64::from(h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            self.draw(ctx, &mut pass, film, placement, exposure_ev, tonemap)?;
        }
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row_bytes),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()?;
        let words = crate::film::read_buffer(ctx, &readback)?;
        let bytes: &[u8] = bytemuck::cast_slice(&words);
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h as usize {
            let row = &bytes[y * row_bytes as usize..][..4 * w as usize];
            out.extend(
                row.chunks_exact(4)
                    .map(|p| if bgra { [p[2], p[1], p[0], p[3]] } else { [p[0], p[1], p[2], p[3]] }),
            );
        }
        Ok(out)
    }
}

crate::gpu_struct! {
    /// The uniform block of [`NoiseEstimator`]'s shader.
    pub struct NoiseParams {
        /// Pixels in the film.
        pub pixels: u32 => WgslType::U32,
        /// Rust-only padding to 16 bytes.
        pub pad: [u32; 3] => WgslType::PAD,
    }
}

/// Workgroups of the noise reduction (each strides over the pixels): 256 partial sums of
/// 16 bytes are read back.
const NOISE_GROUPS: u32 = 256;

/// An estimate of a film's noise, from its per-pixel sample variances of luminance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseEstimate {
    /// Root mean square, over the pixels with at least two samples, of the standard error of
    /// each pixel's mean luminance.
    pub rms_standard_error: f64,
    /// Mean over the pixels with samples of their mean luminance.
    pub mean_luminance: f64,
    /// Pixels with at least two samples (those the error is estimated on).
    pub pixels: u64,
}

impl NoiseEstimate {
    /// The RMS standard error relative to the image's mean luminance (`None` for a black
    /// image): about how far, as a fraction of the image's brightness, a pixel is from its
    /// converged value. Falls as 1/√spp.
    pub fn relative(&self) -> Option<f64> {
        (self.mean_luminance > 0.0).then(|| self.rms_standard_error / self.mean_luminance)
    }
}

fn noise_table() -> BindingTable {
    BindingTable::new(
        0,
        0,
        vec![
            Binding {
                name: "noise",
                ty: NoiseParams::NAME.to_string(),
                kind: BindingKind::Uniform { dynamic: false, min_size: size_of::<NoiseParams>() as u64 },
            },
            Binding::read("film_sum", "array<vec4<f64>>"),
            Binding::read("film_count", "array<vec2<u32>>"),
            Binding::read_write("noise_partial", "array<vec4<f32>>"),
        ],
    )
}

/// Reduces an `f64` film's per-pixel variances (its sums of squared luminances) to a
/// [`NoiseEstimate`] on the GPU.
#[derive(Debug)]
pub struct NoiseEstimator {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    partial: wgpu::Buffer,
}

impl NoiseEstimator {
    /// The estimator, or `None` on a device without `f64` shaders (whose film keeps no squares).
    ///
    /// # Errors
    /// A shader or pipeline error.
    pub fn new(ctx: &GpuContext) -> Result<Option<Self>, GpuError> {
        if !ctx.shader_f64 {
            return Ok(None);
        }
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let table = noise_table();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("noise"),
            entries: &table.layout_entries(),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("noise"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let source = [
            &wgsl_struct::<NoiseParams>(true),
            &table.wgsl(),
            &crate::brdf::luminance_const("NOISE_LUMINANCE"),
            include_str!("wgsl/noise.wgsl"),
        ]
        .concat();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("noise"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("noise"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("noise_main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("noise params"),
            size: size_of::<NoiseParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let partial = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("noise partial sums"),
            size: u64::from(NOISE_GROUPS) * 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Wgpu(e.to_string()));
        }
        Ok(Some(Self { layout, pipeline, params, partial }))
    }

    /// The film's noise now (blocking: waits for the queue, reads back 4 KiB), or `None` when the
    /// film keeps no squares ([`GpuFilm::has_squares`]) or no pixel has two samples.
    ///
    /// # Errors
    /// A device error.
    pub fn estimate(&self, ctx: &GpuContext, film: &GpuFilm) -> Result<Option<NoiseEstimate>, GpuError> {
        let Some(DisplaySource::F64 { sum, count }) = film.display_source() else {
            return Ok(None);
        };
        if !film.has_squares() {
            return Ok(None);
        }
        let pixels = film.width() * film.height();
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&NoiseParams { pixels, pad: [0; 3] }));
        let entries = noise_table().bind_entries(vec![
            self.params.as_entire_binding(),
            sum.as_entire_binding(),
            count.as_entire_binding(),
            self.partial.as_entire_binding(),
        ]);
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("noise"),
            layout: &self.layout,
            entries: &entries,
        });
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(NOISE_GROUPS, 1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        let words = crate::film::read_buffer(ctx, &self.partial)?;
        let v: &[f32] = bytemuck::cast_slice(&words);
        let mut sum = [0f64; 4];
        for c in v.chunks_exact(4) {
            for k in 0..4 {
                sum[k] += f64::from(c[k]);
            }
        }
        let (with_two, with_one) = (sum[2] as u64, sum[3] as u64);
        if with_two == 0 {
            return Ok(None);
        }
        Ok(Some(NoiseEstimate {
            rms_standard_error: (sum[0] / with_two as f64).sqrt(),
            mean_luminance: sum[1] / with_one.max(1) as f64,
            pixels: with_two,
        }))
    }
}
