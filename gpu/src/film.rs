//! [`GpuFilm`]: progressive accumulation on the GPU that does not drift.
//!
//! Accumulates what a [`furnace_render::Film`] holds: per pixel a sum of accepted samples and the counts of
//! accepted and rejected (non-finite) samples; the estimate `sum / count` is formed only when
//! read back. Two precisions, chosen by what the adapter offers ([`FilmPrecision::for_context`]):
//!
//! | precision | WGSL | bytes / pixel on the GPU | error after n samples |
//! |---|---|---|---|
//! | [`FilmPrecision::F64`] | `film_f64.wgsl` | 32 + 8 | ≤ n·2⁻⁵³ relative |
//! | [`FilmPrecision::F32Pass`] | `film_f32.wgsl` | 16 + 8 (+ 32 on the host) | one pass's f32 error, not growing with passes |
//!
//! With `F64` the sums live on the GPU and are bit-identical to the CPU's `f64` sums of the same
//! samples in the same order (`tests/film.rs`). With `F32Pass` the GPU sums one pass in `f32`
//! and [`GpuFilm::fold`] adds it into `f64` sums on the host after each pass. There is no
//! compensated (Neumaier) `f32` film: a GPU compiler may remove its error term (see
//! `film_f32.wgsl`).
//!
//! Both pass the 10⁶-frame drift test (`tests/film.rs`), which the thesis's `f32` running mean
//! fails. A shader that accumulates composes [`FilmPrecision::wgsl`] and declares the film's
//! buffers with [`FilmPrecision::bindings`].

use crate::shared::{Binding, BindingTable};
use crate::{GpuContext, GpuError};
use furnace_render::{AovSum, Film};
use glam::DVec3;
use wgpu::util::DeviceExt;

/// How the film sums samples on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilmPrecision {
    /// `f64` sums (needs [`wgpu::Features::SHADER_F64`]).
    F64,
    /// `f32` sums of one pass on the GPU, added into `f64` sums on the host by [`GpuFilm::fold`].
    F32Pass,
}

impl FilmPrecision {
    /// `F64` when the device has `SHADER_F64`, else `F32Pass`.
    pub fn for_context(ctx: &GpuContext) -> Self {
        if ctx.shader_f64 { Self::F64 } else { Self::F32Pass }
    }

    /// The WGSL module defining `film_add(pixel: u32, value: vec3<f32>)`, with its generated
    /// `FILM_LUMINANCE`.
    pub fn wgsl(self) -> String {
        let module = match self {
            Self::F64 => include_str!("wgsl/film_f64.wgsl"),
            Self::F32Pass => include_str!("wgsl/film_f32.wgsl"),
        };
        crate::brdf::luminance_const("FILM_LUMINANCE") + module
    }

    /// The film's two bindings, `film_sum` and `film_count` (both `read_write` storage).
    pub fn binding_list(self) -> Vec<Binding> {
        let sum_ty = match self {
            Self::F64 => "array<vec4<f64>>",
            Self::F32Pass => "array<vec4<f32>>",
        };
        vec![Binding::read_write("film_sum", sum_ty), Binding::read_write("film_count", "array<vec2<u32>>")]
    }

    /// WGSL declarations of [`FilmPrecision::binding_list`] at `@group(group)`, bindings `first`
    /// and `first + 1`.
    pub fn bindings(self, group: u32, first: u32) -> String {
        BindingTable::new(group, first, self.binding_list()).wgsl()
    }

    /// Bytes of the GPU sum buffer per pixel (the count buffer adds 8).
    pub fn sum_bytes_per_pixel(self) -> u64 {
        match self {
            Self::F64 => 32,
            Self::F32Pass => 16,
        }
    }

    /// The AOV sums' binding, `film_aov` (`read_write` storage, two `vec4` per pixel: albedo and
    /// depth, normal and hits; [`furnace_render::AovSum`]'s layout).
    pub fn aov_binding(self) -> Binding {
        Binding::read_write("film_aov", &format!("array<{}>", self.aov_sum_type()))
    }

    /// The WGSL type of one AOV sum vector: `vec4<f64>` or `vec4<f32>`.
    pub fn aov_sum_type(self) -> &'static str {
        match self {
            Self::F64 => "vec4<f64>",
            Self::F32Pass => "vec4<f32>",
        }
    }
}

/// The film's two storage buffers on the device.
#[derive(Debug)]
pub struct GpuFilm {
    width: u32,
    height: u32,
    precision: FilmPrecision,
    /// Sums: `vec4<f64>` per pixel, or `vec4<f32>` (this pass) for [`FilmPrecision::F32Pass`].
    pub sum: wgpu::Buffer,
    /// `(accepted, rejected)` as `vec2<u32>` per pixel.
    pub count: wgpu::Buffer,
    /// With AOVs: their sums, two `vec4<f64>` (or `vec4<f32>` for this pass) per pixel.
    pub aov: Option<wgpu::Buffer>,
    /// With adaptive sampling: per pixel a `u32`, 1 once it has converged.
    pub converged: Option<wgpu::Buffer>,
    /// [`FilmPrecision::F32Pass`]: the `f64` sums of the passes folded so far.
    host: Option<Film>,
    /// [`FilmPrecision::F32Pass`] with [`GpuFilm::enable_display`]: per pixel
    /// `vec4<f32>(mean rgb, count)` of the folded passes, for a display on the GPU.
    display: Option<wgpu::Buffer>,
    /// Whether the `f64` sums' `w` holds the sum of squared luminances of every sample counted
    /// (false after [`GpuFilm::write`] loaded a film with samples: a saved film has no squares).
    squares_valid: bool,
}

/// Rec. 709 luminance weights: the `f64` film sums each sample's squared luminance with them
/// (`film_f64.wgsl`'s `FILM_LUMINANCE`), for the viewer's noise estimate and adaptive
/// sampling: [`furnace_render::LUMINANCE`].
pub const LUMINANCE: [f32; 3] = furnace_render::LUMINANCE;

/// The buffers a display reads a film from ([`GpuFilm::display_source`]).
#[derive(Debug, Clone, Copy)]
pub enum DisplaySource<'a> {
    /// The `f64` sums (`vec4<f64>`: rgb and the squared luminances) and counts
    /// (`vec2<u32>`) the integrator accumulates into.
    F64 {
        /// `film_sum`.
        sum: &'a wgpu::Buffer,
        /// `film_count`.
        count: &'a wgpu::Buffer,
    },
    /// Per pixel `vec4<f32>(mean rgb, count)`, updated after every fold.
    F32 {
        /// The means.
        means: &'a wgpu::Buffer,
    },
}

/// Bytes per pixel of the sample counts (`vec2<u32>`).
const COUNT_BYTES_PER_PIXEL: u64 = 8;
/// Bytes per pixel of the convergence marks (a `u32`).
const CONVERGED_BYTES_PER_PIXEL: u64 = 4;
/// AOV sums per pixel, each the size of the colour sum (albedo and depth, normal and hits).
const AOV_SUMS: u64 = 2;

impl GpuFilm {
    /// A zeroed film of `width × height` pixels; [`GpuError::TooLarge`] if a buffer would exceed
    /// the adapter's storage binding limit.
    pub fn new(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        precision: FilmPrecision,
    ) -> Result<Self, GpuError> {
        Self::with_parts(ctx, width, height, precision, false, false)
    }

    /// The device bytes of a film [`GpuFilm::with_parts`] makes with these arguments (the display
    /// buffer [`GpuFilm::enable_display`] may add aside).
    pub fn device_bytes(
        width: u32,
        height: u32,
        precision: FilmPrecision,
        aovs: bool,
        adaptive: bool,
    ) -> u64 {
        let pixels = u64::from(width) * u64::from(height);
        let sum = pixels * precision.sum_bytes_per_pixel();
        sum + pixels * COUNT_BYTES_PER_PIXEL
            + if aovs { AOV_SUMS * sum } else { 0 }
            + if adaptive { pixels * CONVERGED_BYTES_PER_PIXEL } else { 0 }
    }

    /// [`GpuFilm::new`], also summing the first-hit AOVs when `aovs` (a third buffer of 64 bytes
    /// per pixel for `F64`, 32 for `F32Pass`), and with adaptive sampling's convergence marks
    /// when `adaptive` (4 bytes per pixel; the squared luminances are the sums' `w`).
    ///
    /// # Errors
    /// [`GpuError::TooLarge`] if a buffer would exceed the adapter's storage binding limit.
    pub fn with_parts(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        precision: FilmPrecision,
        aovs: bool,
        adaptive: bool,
    ) -> Result<Self, GpuError> {
        let pixels = u64::from(width) * u64::from(height);
        let sum_bytes = pixels * precision.sum_bytes_per_pixel();
        let limit = ctx.upload_limit();
        if sum_bytes > limit {
            return Err(GpuError::TooLarge {
                what: format!("a {width}×{height} film"),
                bytes: sum_bytes,
                limit,
            });
        }
        let aov_bytes = AOV_SUMS * sum_bytes;
        if aovs && aov_bytes > limit {
            return Err(GpuError::TooLarge {
                what: format!("the AOVs of a {width}×{height} film"),
                bytes: aov_bytes,
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
        let empty = || {
            let film = if aovs { Film::with_aovs(width, height) } else { Film::new(width, height) };
            if adaptive { film.with_adaptive() } else { film }
        };
        let host = (precision == FilmPrecision::F32Pass).then(empty);
        Ok(Self {
            width,
            height,
            precision,
            sum: make("film sum", sum_bytes),
            count: make("film count", pixels * COUNT_BYTES_PER_PIXEL),
            aov: aovs.then(|| make("film aov", aov_bytes)),
            converged: adaptive.then(|| make("film converged", pixels * CONVERGED_BYTES_PER_PIXEL)),
            host,
            display: None,
            squares_valid: true,
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

    /// Whether it sums AOVs ([`GpuFilm::with_parts`] with `aovs`).
    pub fn has_aovs(&self) -> bool {
        self.aov.is_some()
    }

    /// Makes the film readable by a display on the GPU ([`GpuFilm::display_source`]): nothing
    /// for `F64` (the display reads the sums); for `F32Pass` a buffer of the folded means
    /// (16 bytes per pixel), written after every fold (on such adapters a display costs a
    /// read-back and an upload per pass: the `f64` sums live on the host).
    ///
    /// # Errors
    /// A device error while uploading the means.
    pub fn enable_display(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        if self.host.is_none() || self.display.is_some() {
            return Ok(());
        }
        self.display = Some(ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("film display means"),
            size: (self.pixels() as u64 * 16).max(32),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }));
        self.upload_display(ctx)
    }

    /// What a display reads (call [`GpuFilm::enable_display`] first); `None` for an `F32Pass`
    /// film without a display buffer.
    pub fn display_source(&self) -> Option<DisplaySource<'_>> {
        match self.precision {
            FilmPrecision::F64 => Some(DisplaySource::F64 { sum: &self.sum, count: &self.count }),
            FilmPrecision::F32Pass => self.display.as_ref().map(|means| DisplaySource::F32 { means }),
        }
    }

    /// Whether the sums' `w` holds every counted sample's squared luminance (an `F64` film not
    /// loaded from a saved one since it was last cleared): the noise estimate needs it.
    pub fn has_squares(&self) -> bool {
        self.precision == FilmPrecision::F64 && self.squares_valid
    }

    /// `F32Pass` with a display: uploads the folded means (the GPU's pass sums are zero then).
    fn upload_display(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        let (Some(buffer), Some(host)) = (&self.display, &self.host) else {
            return Ok(());
        };
        let means: Vec<f32> = (0..self.pixels())
            .flat_map(|i| {
                let m = host.mean(i).as_vec3();
                [m.x, m.y, m.z, host.counts()[i] as f32]
            })
            .collect();
        ctx.queue.write_buffer(buffer, 0, bytemuck::cast_slice(&means));
        ctx.queue.submit([]);
        ctx.check()
    }

    fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Bind group layout entries of the two buffers at bindings `first`, `first + 1`.
    pub fn layout_entries(first: u32) -> Vec<wgpu::BindGroupLayoutEntry> {
        BindingTable::new(0, first, FilmPrecision::F64.binding_list()).layout_entries()
    }

    /// The buffers of [`FilmPrecision::binding_list`], in its order.
    pub fn resources(&self) -> Vec<wgpu::BindingResource<'_>> {
        vec![self.sum.as_entire_binding(), self.count.as_entire_binding()]
    }

    /// Bind group entries matching [`GpuFilm::layout_entries`].
    pub fn bind_entries(&self, first: u32) -> Vec<wgpu::BindGroupEntry<'_>> {
        BindingTable::new(0, first, self.precision.binding_list()).bind_entries(self.resources())
    }

    /// Zeroes every pixel.
    pub fn clear(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        if let Some(h) = &mut self.host {
            h.clear();
        }
        self.squares_valid = true;
        self.clear_device(ctx)?;
        self.upload_converged(ctx)?;
        self.upload_display(ctx)
    }

    /// `F32Pass` with adaptive sampling: uploads the host's convergence marks (the GPU reads
    /// them to skip converged pixels); nothing otherwise.
    fn upload_converged(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        let (Some(buffer), Some(host)) = (&self.converged, &self.host) else { return Ok(()) };
        let Some(marks) = host.converged() else { return Ok(()) };
        write_marks(ctx, buffer, marks);
        ctx.queue.submit([]);
        ctx.check()
    }

    /// With adaptive sampling: replaces the convergence marks (the host's for `F32Pass`, the
    /// GPU's for `F64`), the sums untouched; nothing without adaptive sampling.
    ///
    /// # Errors
    /// [`GpuError::Wgpu`] naming both counts unless there is one mark per pixel; a device error.
    pub fn set_marks(&mut self, ctx: &GpuContext, marks: &[bool]) -> Result<(), GpuError> {
        let Some(buffer) = &self.converged else { return Ok(()) };
        if marks.len() != self.pixels() {
            return Err(GpuError::Wgpu(format!(
                "{} convergence marks for a {}×{} film",
                marks.len(),
                self.width,
                self.height
            )));
        }
        if let Some(h) = &mut self.host {
            h.set_converged(marks).map_err(|e| GpuError::Wgpu(e.to_string()))?;
            return self.upload_converged(ctx);
        }
        write_marks(ctx, buffer, marks);
        ctx.queue.submit([]);
        ctx.check()
    }

    /// `F32Pass` with adaptive sampling: tests the folded film on the host and uploads the
    /// marks; returns how many pixels have converged. `None` for other films (an `F64` film is
    /// tested on the GPU by the integrator's `converge` kernel).
    pub fn test_convergence_on_host(
        &mut self,
        ctx: &GpuContext,
        rule: &furnace_render::AdaptiveSampling,
    ) -> Result<Option<u64>, GpuError> {
        if self.converged.is_none() {
            return Ok(None);
        }
        let Some(h) = &mut self.host else { return Ok(None) };
        let n = h.test_convergence(rule);
        self.upload_converged(ctx)?;
        Ok(Some(n))
    }

    /// `F32Pass`: how many pixels the host's marks say have converged.
    pub fn host_converged_count(&self) -> Option<u64> {
        self.host.as_ref().and_then(Film::converged_count)
    }

    /// The device buffers a pass changes and a stopped pass must give back: for `F64` the sums,
    /// counts, AOV sums and convergence marks; none for `F32Pass`, whose device buffers hold
    /// only the pass in progress ([`GpuFilm::drop_pass`] clears them).
    pub fn pass_state(&self) -> Vec<&wgpu::Buffer> {
        if self.host.is_some() {
            return Vec::new();
        }
        [Some(&self.sum), Some(&self.count), self.aov.as_ref(), self.converged.as_ref()]
            .into_iter()
            .flatten()
            .collect()
    }

    /// Drops an unfinished `F32Pass` pass (its device sums and counts zeroed); nothing for `F64`
    /// (its buffers are restored from the copies of [`GpuFilm::pass_state`]).
    pub fn drop_pass(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        if self.host.is_none() { Ok(()) } else { self.clear_device(ctx) }
    }

    fn clear_device(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.sum, 0, None);
        enc.clear_buffer(&self.count, 0, None);
        if let Some(aov) = &self.aov {
            enc.clear_buffer(aov, 0, None);
        }
        if self.host.is_none()
            && let Some(c) = &self.converged
        {
            enc.clear_buffer(c, 0, None);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.wait()
    }

    /// After a pass: for [`FilmPrecision::F32Pass`], adds the GPU's pass sums into the host's
    /// `f64` sums and zeroes the GPU's; nothing for `F64`. Call it after every pass, at most
    /// 2¹⁶ samples per pixel apart (beyond that the `f32` pass sum loses digits).
    pub fn fold(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        if self.host.is_none() {
            return Ok(());
        }
        let pass = self.read_device(ctx)?;
        if let Some(h) = &mut self.host {
            h.add_film(&pass).map_err(|e| GpuError::Wgpu(e.to_string()))?;
        }
        self.clear_device(ctx)?;
        self.upload_display(ctx)
    }

    /// The film: sums in `f64`, counts, and the total of rejected samples (for `F32Pass`, the
    /// folded passes plus the pass in progress).
    pub fn read(&self, ctx: &GpuContext) -> Result<Film, GpuError> {
        let device = self.read_device(ctx)?;
        Ok(match &self.host {
            None => device,
            Some(h) => {
                let mut total = h.clone();
                total.add_film(&device).map_err(|e| GpuError::Wgpu(e.to_string()))?;
                total
            }
        })
    }

    /// The device's film. Its buffers are copied to staging buffers in one submission and
    /// converted straight from the mapped memory (a 4K `F64` film's sums are 265 MB: no copy of
    /// them is made on the host before they are turned into the film's).
    fn read_device(&self, ctx: &GpuContext) -> Result<Film, GpuError> {
        let n = self.pixels();
        // Convergence marks are the GPU's only for `F64` (`F32Pass`: the host's, kept by
        // `Film::add_film`).
        let converged = self.converged.as_ref().filter(|_| self.host.is_none());
        let mut buffers = vec![&self.sum, &self.count];
        buffers.extend(converged);
        buffers.extend(&self.aov);
        read_buffers(ctx, &buffers, |words| {
            let (sum_words, count_words) = (words[0], words[1]);
            let adaptive = self.converged.is_some();
            let (sum, lum_sq) = match self.precision {
                FilmPrecision::F64 => sums_and_squares::<f64>(&sum_words[..n * 8], adaptive),
                FilmPrecision::F32Pass => sums_and_squares::<f32>(&sum_words[..n * 4], adaptive),
            };
            let pairs = &count_words[..2 * n];
            let count = pairs.chunks_exact(2).map(|c| u64::from(c[0])).collect();
            let rejected = pairs.chunks_exact(2).map(|c| u64::from(c[1])).sum();
            let mut film = Film::from_parts(self.width, self.height, sum, count, rejected)
                .map_err(|e| GpuError::Wgpu(e.to_string()))?;
            let mut next = 2;
            if let Some(lum_sq) = lum_sq {
                // The marks are the GPU's (F64) or the host's (F32Pass: these are zero,
                // Film::add_film keeps the host's).
                let marks = match converged {
                    Some(_) => {
                        next += 1;
                        words[2][..n].iter().map(|&w| w != 0).collect()
                    }
                    None => vec![false; n],
                };
                film = film.with_adaptive_state(lum_sq, marks).map_err(|e| GpuError::Wgpu(e.to_string()))?;
            }
            if self.aov.is_none() {
                return Ok(film);
            }
            let words = words[next];
            let sums: Vec<AovSum> = match self.precision {
                FilmPrecision::F64 => pod_words::<f64>(&words[..n * 16])
                    .chunks_exact(8)
                    .map(|c| AovSum::from_array(c.try_into().expect("8 sums")))
                    .collect(),
                FilmPrecision::F32Pass => pod_words::<f32>(&words[..n * 8])
                    .chunks_exact(8)
                    .map(|c| AovSum::from_array(std::array::from_fn(|k| f64::from(c[k]))))
                    .collect(),
            };
            film.with_aov_sums(sums).map_err(|e| GpuError::Wgpu(e.to_string()))
        })?
    }

    /// Loads a film (to resume a render). `F64`: uploaded as is (rejected samples are
    /// attributed to pixel 0, only their total is kept); `F32Pass`: kept on the host, the GPU
    /// zeroed. Errors if the size differs or, for `F64`, a count exceeds `u32::MAX`.
    pub fn write(&mut self, ctx: &GpuContext, data: &Film) -> Result<(), GpuError> {
        let n = self.pixels();
        if (data.width(), data.height()) != (self.width, self.height) {
            return Err(GpuError::FilmSize {
                film_width: data.width(),
                film_height: data.height(),
                width: self.width,
                height: self.height,
            });
        }
        if data.has_aovs() != self.has_aovs() {
            return Err(GpuError::FilmAovs { film_has_aovs: data.has_aovs() });
        }
        if data.has_adaptive() != self.converged.is_some() {
            return Err(GpuError::FilmAdaptive { film_has_state: data.has_adaptive() });
        }
        // A saved film carries its squared luminances only with adaptive state.
        self.squares_valid = data.counts().iter().all(|&c| c == 0) || data.has_adaptive();
        if let Some(h) = &mut self.host {
            *h = data.clone();
            self.clear_device(ctx)?;
            self.upload_converged(ctx)?;
            return self.upload_display(ctx);
        }
        let too_many = |c: u64| {
            u32::try_from(c).map_err(|_| {
                GpuError::Wgpu(format!("{c} samples in one pixel exceed the GPU film's u32 count"))
            })
        };
        let mut counts = Vec::with_capacity(2 * n);
        for (i, &c) in data.counts().iter().enumerate() {
            counts.push(too_many(c)?);
            counts.push(if i == 0 { too_many(data.rejected())? } else { 0 });
        }
        let squares = data.lum_sq_sums();
        let v: Vec<f64> = data
            .sums()
            .iter()
            .enumerate()
            .flat_map(|(i, s)| [s.x, s.y, s.z, squares.map_or(0.0, |q| q[i])])
            .collect();
        if let (Some(buffer), Some(marks)) = (&self.converged, data.converged()) {
            write_marks(ctx, buffer, marks);
        }
        ctx.queue.write_buffer(&self.sum, 0, bytemuck::cast_slice(&v));
        ctx.queue.write_buffer(&self.count, 0, bytemuck::cast_slice(&counts));
        if let (Some(buffer), Some(sums)) = (&self.aov, data.aov_sums()) {
            let v: Vec<f64> = sums.iter().flat_map(AovSum::to_array).collect();
            ctx.queue.write_buffer(buffer, 0, bytemuck::cast_slice(&v));
        }
        ctx.queue.submit([]);
        ctx.wait()
    }
}

/// Queues the upload of convergence marks as the GPU's `u32` per pixel (1: converged).
fn write_marks(ctx: &GpuContext, buffer: &wgpu::Buffer, marks: &[bool]) {
    let words: Vec<u32> = marks.iter().map(|&c| u32::from(c)).collect();
    ctx.queue.write_buffer(buffer, 0, bytemuck::cast_slice(&words));
}

/// Copies a whole buffer (created with `COPY_SRC`) back as `u32` words.
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u32>, GpuError> {
    read_buffers(ctx, &[buffer], |words| words[0].to_vec())
}

/// Copies whole buffers (created with `COPY_SRC`) to staging buffers in one submission, waits
/// once, and gives `read` their contents as `u32` words, in `buffers`' order, while they are
/// mapped: `read` converts them without a copy on the host first.
pub fn read_buffers<T>(
    ctx: &GpuContext,
    buffers: &[&wgpu::Buffer],
    read: impl FnOnce(&[&[u32]]) -> T,
) -> Result<T, GpuError> {
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    let staging: Vec<wgpu::Buffer> = buffers
        .iter()
        .map(|buffer| {
            let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: buffer.size(),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
            staging
        })
        .collect();
    ctx.queue.submit([enc.finish()]);
    for s in &staging {
        s.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    }
    ctx.wait()?;
    let views = staging
        .iter()
        .map(|s| s.slice(..).get_mapped_range().map_err(|e| GpuError::Wgpu(e.to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    // Mapped ranges are aligned to at least `wgpu::MAP_ALIGNMENT` (8 bytes); a view that were
    // not would be copied into words.
    let copies: Vec<Option<Vec<u32>>> = views
        .iter()
        .map(|v| bytemuck::try_cast_slice::<u8, u32>(v).is_err().then(|| bytemuck::pod_collect_to_vec(v)))
        .collect();
    let words: Vec<&[u32]> = views
        .iter()
        .zip(&copies)
        .map(|(v, c)| c.as_deref().unwrap_or_else(|| bytemuck::cast_slice(v)))
        .collect();
    let result = read(&words);
    drop(words);
    drop(views);
    for s in &staging {
        s.unmap();
    }
    Ok(result)
}

/// A film's `[r, g, b, squared luminance]` sums per pixel (`words`, as `T`s) as the RGB sums
/// and, with `squares`, the squared luminances.
fn sums_and_squares<T: bytemuck::Pod + Into<f64>>(
    words: &[u32],
    squares: bool,
) -> (Vec<DVec3>, Option<Vec<f64>>) {
    let v = pod_words::<T>(words);
    let sum = v.chunks_exact(4).map(|c| DVec3::new(c[0].into(), c[1].into(), c[2].into())).collect();
    (sum, squares.then(|| v.chunks_exact(4).map(|c| c[3].into()).collect()))
}

/// `words` as `T`s (`f32` or `f64`), copied only where they are not aligned for `T` (mapped
/// ranges are).
fn pod_words<T: bytemuck::Pod>(words: &[u32]) -> std::borrow::Cow<'_, [T]> {
    match bytemuck::try_cast_slice(words) {
        Ok(v) => std::borrow::Cow::Borrowed(v),
        Err(_) => std::borrow::Cow::Owned(bytemuck::pod_collect_to_vec(words)),
    }
}

/// A uniform buffer holding `words`.
pub fn uniform(ctx: &GpuContext, words: &[u32]) -> wgpu::Buffer {
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("uniform"),
        contents: bytemuck::cast_slice(words),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}
