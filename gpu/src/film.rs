//! [`GpuFilm`]: progressive accumulation on the GPU that does not drift.
//!
//! The twin of furnace-cpu's `Film`: per pixel a sum of accepted samples and the counts of
//! accepted and rejected (non-finite) samples; the estimate `sum / count` is formed only when
//! read back. Two precisions, chosen by what the adapter offers ([`FilmPrecision::for_context`]):
//!
//! | precision | WGSL | bytes / pixel | error after n samples |
//! |---|---|---|---|
//! | [`FilmPrecision::F64`] | `film_f64.wgsl` | 32 + 8 | ≤ n·2⁻⁵³ relative |
//! | [`FilmPrecision::CompensatedF32`] | `film_f32.wgsl` (Neumaier) | 32 + 8 | ≈ 2·2⁻²⁴, independent of n |
//!
//! Both pass the 10⁶-frame drift test (`tests/film.rs`), which the thesis's `f32` running mean
//! fails. A shader that accumulates composes [`FilmPrecision::wgsl`] and declares the film's
//! buffers with [`FilmPrecision::bindings`].

use crate::{GpuContext, GpuError};
use wgpu::util::DeviceExt;

/// How the film sums samples on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilmPrecision {
    /// `f64` sums (needs [`wgpu::Features::SHADER_F64`]).
    F64,
    /// Compensated (Neumaier) `f32` sums: a sum and a compensation per channel.
    CompensatedF32,
}

impl FilmPrecision {
    /// `F64` when the device has `SHADER_F64`, else `CompensatedF32`.
    pub fn for_context(ctx: &GpuContext) -> Self {
        if ctx.shader_f64 { Self::F64 } else { Self::CompensatedF32 }
    }

    /// The WGSL module defining `film_add(pixel: u32, value: vec3<f32>)`.
    pub fn wgsl(self) -> &'static str {
        match self {
            Self::F64 => include_str!("wgsl/film_f64.wgsl"),
            Self::CompensatedF32 => include_str!("wgsl/film_f32.wgsl"),
        }
    }

    /// WGSL declarations of `film_sum` and `film_count` at `@group(group)`, bindings `first` and
    /// `first + 1` (both `read_write` storage).
    pub fn bindings(self, group: u32, first: u32) -> String {
        let sum_ty = match self {
            Self::F64 => "array<vec4<f64>>",
            Self::CompensatedF32 => "array<vec4<f32>>",
        };
        format!(
            "@group({group}) @binding({first}) var<storage, read_write> film_sum: {sum_ty};\n\
             @group({group}) @binding({}) var<storage, read_write> film_count: array<vec2<u32>>;\n",
            first + 1
        )
    }

    /// Bytes of the sum buffer per pixel (the count buffer adds 8).
    pub fn sum_bytes_per_pixel(self) -> u64 {
        32
    }
}

/// A film read back from (or written to) the GPU: what resuming and image output need.
#[derive(Debug, Clone, PartialEq)]
pub struct FilmData {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Per pixel (row-major, row 0 at the top): the sum of accepted samples, linear RGB.
    pub sum: Vec<[f64; 3]>,
    /// Per pixel: accepted samples.
    pub count: Vec<u64>,
    /// Rejected (non-finite) samples, all pixels together.
    pub rejected: u64,
}

impl FilmData {
    /// Pixel `i`'s mean (0 without samples).
    pub fn mean(&self, i: usize) -> [f64; 3] {
        let n = self.count[i];
        if n == 0 { [0.0; 3] } else { self.sum[i].map(|s| s / n as f64) }
    }
}

/// The film's two storage buffers on the device.
#[derive(Debug)]
pub struct GpuFilm {
    width: u32,
    height: u32,
    precision: FilmPrecision,
    /// Sums: `vec4<f64>` per pixel, or two `vec4<f32>` (sum, compensation).
    pub sum: wgpu::Buffer,
    /// `(accepted, rejected)` as `vec2<u32>` per pixel.
    pub count: wgpu::Buffer,
}

impl GpuFilm {
    /// A zeroed film of `width × height` pixels; [`GpuError::TooLarge`] if a buffer would exceed
    /// the adapter's storage binding limit.
    pub fn new(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        precision: FilmPrecision,
    ) -> Result<Self, GpuError> {
        let pixels = u64::from(width) * u64::from(height);
        let sum_bytes = pixels * precision.sum_bytes_per_pixel();
        let limit = ctx.max_storage_binding().min(ctx.device.limits().max_buffer_size);
        if sum_bytes > limit {
            return Err(GpuError::TooLarge {
                what: format!("a {width}×{height} film"),
                bytes: sum_bytes,
                limit,
            });
        }
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let make = |label, size: u64| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(32),
                usage,
                mapped_at_creation: false,
            })
        };
        Ok(Self {
            width,
            height,
            precision,
            sum: make("film sum", sum_bytes),
            count: make("film count", pixels * 8),
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// How it sums.
    pub fn precision(&self) -> FilmPrecision {
        self.precision
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Bind group layout entries of the two buffers at bindings `first`, `first + 1`.
    pub fn layout_entries(first: u32) -> [wgpu::BindGroupLayoutEntry; 2] {
        let e = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        [e(first), e(first + 1)]
    }

    /// Bind group entries matching [`GpuFilm::layout_entries`].
    pub fn bind_entries(&self, first: u32) -> [wgpu::BindGroupEntry<'_>; 2] {
        [
            wgpu::BindGroupEntry { binding: first, resource: self.sum.as_entire_binding() },
            wgpu::BindGroupEntry { binding: first + 1, resource: self.count.as_entire_binding() },
        ]
    }

    /// Zeroes every pixel.
    pub fn clear(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.sum, 0, None);
        enc.clear_buffer(&self.count, 0, None);
        ctx.queue.submit([enc.finish()]);
        ctx.wait()
    }

    /// Copies the film back: sums in `f64` (for compensated `f32`, sum + compensation formed in
    /// `f64`), counts, and the total of rejected samples.
    pub fn read(&self, ctx: &GpuContext) -> Result<FilmData, GpuError> {
        let sum_words: Vec<u32> = read_buffer(ctx, &self.sum)?;
        let count_words: Vec<u32> = read_buffer(ctx, &self.count)?;
        let n = self.pixels();
        let sum = match self.precision {
            FilmPrecision::F64 => {
                let v: &[f64] = bytemuck::cast_slice(&sum_words[..n * 8]);
                v.chunks_exact(4).map(|c| [c[0], c[1], c[2]]).collect()
            }
            FilmPrecision::CompensatedF32 => {
                let v: &[f32] = bytemuck::cast_slice(&sum_words[..n * 8]);
                v.chunks_exact(8)
                    .map(|c| std::array::from_fn(|k| f64::from(c[k]) + f64::from(c[4 + k])))
                    .collect()
            }
        };
        let count = count_words[..2 * n].chunks_exact(2).map(|c| u64::from(c[0])).collect();
        let rejected = count_words[..2 * n].chunks_exact(2).map(|c| u64::from(c[1])).sum();
        Ok(FilmData { width: self.width, height: self.height, sum, count, rejected })
    }

    /// Uploads a film (to resume a render). For compensated `f32`, each sum is split into its
    /// nearest `f32` and the remainder. Rejected samples are attributed to pixel 0 (only their
    /// total is kept). Errors if the size differs or a count exceeds `u32::MAX`.
    pub fn write(&self, ctx: &GpuContext, data: &FilmData) -> Result<(), GpuError> {
        let n = self.pixels();
        if (data.width, data.height) != (self.width, self.height)
            || data.sum.len() != n
            || data.count.len() != n
        {
            return Err(GpuError::Wgpu(format!(
                "film of {}×{} cannot be loaded into a {}×{} film",
                data.width, data.height, self.width, self.height
            )));
        }
        let too_many = |c: u64| {
            u32::try_from(c).map_err(|_| {
                GpuError::Wgpu(format!("{c} samples in one pixel exceed the GPU film's u32 count"))
            })
        };
        let mut counts = Vec::with_capacity(2 * n);
        for (i, &c) in data.count.iter().enumerate() {
            counts.push(too_many(c)?);
            counts.push(if i == 0 { too_many(data.rejected)? } else { 0 });
        }
        let sum_bytes: Vec<u8> = match self.precision {
            FilmPrecision::F64 => {
                let v: Vec<f64> = data.sum.iter().flat_map(|s| [s[0], s[1], s[2], 0.0]).collect();
                bytemuck::cast_slice(&v).to_vec()
            }
            FilmPrecision::CompensatedF32 => {
                let v: Vec<f32> = data
                    .sum
                    .iter()
                    .flat_map(|s| {
                        let hi = s.map(|x| x as f32);
                        let lo: [f32; 3] = std::array::from_fn(|k| (s[k] - f64::from(hi[k])) as f32);
                        [hi[0], hi[1], hi[2], 0.0, lo[0], lo[1], lo[2], 0.0]
                    })
                    .collect();
                bytemuck::cast_slice(&v).to_vec()
            }
        };
        ctx.queue.write_buffer(&self.sum, 0, &sum_bytes);
        ctx.queue.write_buffer(&self.count, 0, bytemuck::cast_slice(&counts));
        ctx.queue.submit([]);
        ctx.wait()
    }
}

/// Copies a whole buffer (created with `COPY_SRC`) back as `u32` words.
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u32>, GpuError> {
    let size = buffer.size();
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    ctx.queue.submit([enc.finish()]);
    staging.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    ctx.wait()?;
    let view = staging.slice(..).get_mapped_range().map_err(|e| GpuError::Wgpu(e.to_string()))?;
    let words = bytemuck::cast_slice(&view).to_vec();
    drop(view);
    staging.unmap();
    Ok(words)
}

/// A uniform buffer holding `words`.
pub fn uniform(ctx: &GpuContext, words: &[u32]) -> wgpu::Buffer {
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("uniform"),
        contents: bytemuck::cast_slice(words),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}
