//! [`GpuRenderer::render_pass`]: a pass cut into blocks and dispatches, each dispatch's uniform
//! slot, the bind group, and the submission — in one, or dispatch by dispatch where a cancel flag
//! must be answered — with adaptive sampling's test and the pass's GPU time.

use super::dispatch::{Block, LONG_PASS_SECONDS, SLOT, Step};
use super::{FrameParams, GpuRenderer, binding_table, tile_of};
use crate::GpuError;
use furnace_render::{ADAPTIVE_STEP, Film};

#[cfg(doc)]
use crate::film::GpuFilm;

/// GPU timestamps around each pass's compute pass (adapters with `TIMESTAMP_QUERY`).
#[derive(Debug)]
pub(super) struct Timer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    period_ns: f32,
    /// The GPU seconds of the last pass (`None` for a pass submitted dispatch by dispatch).
    last: Option<f64>,
}

impl Timer {
    /// The seconds between the timestamps the last pass submitted in one wrote.
    fn read_seconds(&self, ctx: &crate::GpuContext) -> Result<f64, GpuError> {
        let w = crate::film::read_buffer(ctx, &self.resolve)?;
        let (begin, end) = (u64::from(w[0]) | u64::from(w[1]) << 32, u64::from(w[2]) | u64::from(w[3]) << 32);
        Ok(end.wrapping_sub(begin) as f64 * f64::from(self.period_ns) * 1e-9)
    }
}

impl GpuRenderer {
    /// Whether passes record GPU timestamps (where the adapter has `TIMESTAMP_QUERY`): then
    /// [`GpuRenderer::last_pass_gpu_seconds`] gives each pass's time on the GPU. Returns whether
    /// timing is on.
    pub fn set_timing(&mut self, on: bool) -> bool {
        if !on || !self.ctx.device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            self.timer = None;
            return false;
        }
        if self.timer.is_none() {
            let d = &self.ctx.device;
            self.timer = Some(Timer {
                queries: d.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                }),
                resolve: d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: 16,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                period_ns: self.ctx.queue.get_timestamp_period(),
                last: None,
            });
        }
        true
    }

    /// The GPU time of the last pass's compute work, from its timestamps (timing on).
    pub fn last_pass_gpu_seconds(&self) -> Option<f64> {
        self.timer.as_ref().and_then(|t| t.last)
    }

    /// Adds samples `first_sample .. first_sample + samples_per_pixel` of every pixel to the film
    /// (then folds an `F32Pass` film). Errors as the CPU's for a fixed-N sampler run past N, and
    /// on any device error (validation, out of memory, device lost).
    pub fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), GpuError> {
        if samples_per_pixel == 0 || self.settings.width == 0 || self.settings.height == 0 {
            return Ok(());
        }
        self.sampler.check_index(first_sample.saturating_add(samples_per_pixel - 1))?;
        let end = first_sample.saturating_add(samples_per_pixel);
        let Some(rule) = self.settings.adaptive else {
            let group_samples = self.group_samples(samples_per_pixel);
            let start = std::time::Instant::now();
            self.render_blocks(&[Block { first: first_sample, end, converge: false }])?;
            if let Some(t) = &mut self.tuner {
                t.record(group_samples, samples_per_pixel, start.elapsed().as_secs_f64());
            }
            return self.film.fold(&self.ctx);
        };
        // Adaptive sampling tests pixels at multiples of ADAPTIVE_STEP: blocks that end there,
        // each followed by the test where it applies.
        let mut blocks = Vec::new();
        let mut block = first_sample;
        while block < end {
            let block_end = (block / ADAPTIVE_STEP + 1).saturating_mul(ADAPTIVE_STEP).min(end);
            let converge = self.convergence_tests && rule.tests_at(block_end);
            blocks.push(Block { first: block, end: block_end, converge });
            block = block_end;
        }
        if self.kernel.converge.is_some() {
            // An f64 film: every block and test in one submission, the count read once.
            self.render_blocks(&blocks)?;
            if blocks.iter().any(|b| b.converge) {
                self.converged = Some(self.read_converged_counter()?);
            }
            return Ok(());
        }
        // An F32Pass film: each block folded on the host and tested there.
        let mut total = Some(0.0);
        for b in &blocks {
            let seconds = self.render_blocks(&[Block { converge: false, ..*b }]).map_err(|e| match e {
                GpuError::Interrupted { .. } => GpuError::Interrupted { samples: b.first - first_sample },
                e => e,
            })?;
            total = total.zip(seconds).map(|(a, b)| a + b);
            self.film.fold(&self.ctx)?;
            if b.converge {
                self.converged = self.film.test_convergence_on_host(&self.ctx, &rule)?;
            }
        }
        if let Some(t) = &mut self.timer {
            t.last = total;
        }
        Ok(())
    }

    /// With adaptive sampling: whether passes run its test at its test points (the default), or
    /// only skip the pixels already marked converged — for a caller that tests the film
    /// itself, as [`crate::MultiGpuRenderer`] tests the sum of its devices' films, then marks
    /// them with [`GpuRenderer::set_converged`].
    pub fn set_convergence_tests(&mut self, on: bool) {
        self.convergence_tests = on;
    }

    /// With adaptive sampling: replaces the film's convergence marks (one per pixel, row-major;
    /// marked pixels take no more samples), leaving its sums as they are; nothing without it.
    ///
    /// # Errors
    /// As [`GpuFilm::set_marks`]: `marks` must hold one mark per pixel.
    pub fn set_converged(&mut self, marks: &[bool]) -> Result<(), GpuError> {
        if self.settings.adaptive.is_none() {
            return Ok(());
        }
        self.film.set_marks(&self.ctx, marks)?;
        let n = marks.iter().filter(|&&m| m).count() as u64;
        self.converged = Some(n);
        self.write_converged_counter(n)
    }

    /// The GPU's count of converged pixels (kept by the `converge` kernel).
    fn read_converged_counter(&self) -> Result<u64, GpuError> {
        let Some(counter) = &self.converged_counter else { return Ok(0) };
        Ok(u64::from(crate::film::read_buffer(&self.ctx, counter)?[0]))
    }

    /// Sets the GPU's count of converged pixels (after a film was loaded or cleared).
    pub(super) fn write_converged_counter(&self, n: u64) -> Result<(), GpuError> {
        if let Some(counter) = &self.converged_counter {
            let n = u32::try_from(n).map_err(|_| GpuError::Wgpu(format!("{n} converged pixels")))?;
            self.ctx.queue.write_buffer(counter, 0, bytemuck::cast_slice(&[n, 0, 0, 0]));
            self.ctx.queue.submit([]);
            self.ctx.wait()?;
        }
        Ok(())
    }

    /// Records one step of a pass into `pass`.
    fn record_step(&self, pass: &mut wgpu::ComputePass<'_>, step: Step, bind: &wgpu::BindGroup) {
        match step {
            Step::Samples { slot, groups_y, tile_width } => {
                pass.set_pipeline(&self.kernel.main);
                pass.set_bind_group(0, bind, &[(slot as u64 * SLOT) as u32]);
                pass.dispatch_workgroups(self.settings.width.div_ceil(tile_width), groups_y, 1);
            }
            Step::Converge => {
                let Some(pipeline) = &self.kernel.converge else { return };
                // After the block's samples (wgpu orders the dispatches' storage accesses):
                // every pixel not yet converged tested once, the newly converged counted.
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind, &[0]);
                let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
                let groups = pixels.div_ceil(u64::from(self.kernel.group_size));
                let x = groups.clamp(1, 65_535) as u32;
                pass.dispatch_workgroups(x, groups.div_ceil(u64::from(x)).max(1) as u32, 1);
            }
        }
    }

    /// Submits `steps` one submission each, polling the cancel flag after each: raised before
    /// the last, the film is given back as it was before the pass (`F64`: from copies taken
    /// first; `F32Pass`: its pass buffers cleared) and [`GpuError::Interrupted`] returned.
    /// Returns the longest dispatch of samples, in seconds.
    fn submit_steps_one_by_one(&mut self, steps: &[Step], bind: &wgpu::BindGroup) -> Result<f64, GpuError> {
        let mut state = self.film.pass_state();
        state.extend(&self.converged_counter);
        if self.pass_backup.len() != state.len() {
            self.pass_backup = state
                .iter()
                .map(|b| {
                    self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("pass backup"),
                        size: b.size(),
                        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    })
                })
                .collect();
        }
        let copy = |from: &[&wgpu::Buffer], to: &[&wgpu::Buffer]| {
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            for (a, b) in from.iter().zip(to) {
                encoder.copy_buffer_to_buffer(a, 0, b, 0, a.size());
            }
            encoder.finish()
        };
        let backup: Vec<&wgpu::Buffer> = self.pass_backup.iter().collect();
        if !state.is_empty() {
            self.ctx.queue.submit([copy(&state, &backup)]);
        }
        let cancel = self.cancel.clone().unwrap_or_default();
        let mut longest = 0.0f64;
        for (k, step) in steps.iter().enumerate() {
            let started = std::time::Instant::now();
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("integrator"),
                    timestamp_writes: None,
                });
                self.record_step(&mut pass, *step, bind);
            }
            self.ctx.queue.submit([encoder.finish()]);
            self.ctx.wait()?;
            if matches!(step, Step::Samples { .. }) {
                longest = longest.max(started.elapsed().as_secs_f64());
            }
            if cancel.is_raised() && k + 1 < steps.len() {
                if !state.is_empty() {
                    self.ctx.queue.submit([copy(&backup, &state)]);
                    self.ctx.wait()?;
                }
                self.film.drop_pass(&self.ctx)?;
                self.sizing.fit(longest);
                return Err(GpuError::Interrupted { samples: 0 });
            }
        }
        Ok(longest)
    }

    /// The uniform slots and the steps of `blocks`, in order: per block its dispatches, a slot
    /// each, then (with `converge`, where the GPU tests) adaptive sampling's test.
    fn plan(&self, blocks: &[Block]) -> (Vec<FrameParams>, Vec<Step>) {
        let mut slots: Vec<FrameParams> = Vec::new();
        let mut steps = Vec::new();
        let size = (self.settings.width, self.settings.height);
        for b in blocks {
            let group_samples = self.group_samples(b.end - b.first);
            let (tile_width, tile_height) = tile_of(self.kernel.group_size, group_samples);
            for d in self.sizing.dispatches(size, b.first, b.end - b.first, group_samples, tile_height) {
                let groups_y = d.rows.div_ceil(tile_height);
                steps.push(Step::Samples { slot: slots.len(), groups_y, tile_width });
                slots.push(FrameParams {
                    first_sample: d.first_sample,
                    samples: d.samples,
                    row_offset: d.row_offset,
                    group_samples,
                    tile_width,
                    ..self.base
                });
            }
            if b.converge && self.kernel.converge.is_some() {
                steps.push(Step::Converge);
            }
        }
        (slots, steps)
    }

    /// The bind group of a pass: the uniform buffer of `slots` ([`SLOT`] bytes apart; returned
    /// with it, to outlive the pass) and the buffers of [`binding_table`], in its order.
    fn bind_group(&self, slots: &[FrameParams]) -> Result<(wgpu::Buffer, wgpu::BindGroup), GpuError> {
        let mut bytes = vec![0u8; slots.len().max(1) * SLOT as usize];
        for (k, p) in slots.iter().enumerate() {
            bytes[k * SLOT as usize..][..size_of::<FrameParams>()].copy_from_slice(bytemuck::bytes_of(p));
        }
        let params = self.ctx.buffer_init("frame params", &bytes, wgpu::BufferUsages::UNIFORM)?;
        let mut resources = vec![wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &params,
            offset: 0,
            size: wgpu::BufferSize::new(size_of::<FrameParams>() as u64),
        })];
        resources.extend(self.film.resources());
        resources.extend(self.bvh.iter().map(wgpu::Buffer::as_entire_binding));
        resources.extend(self.scene.resources());
        resources.push(self.turquin.as_entire_binding());
        resources.push(self.point_lights.as_entire_binding());
        if let Some(t) = &self.scene.transmission {
            resources.push(t.as_entire_binding());
        }
        if let Some(l) = &self.scene.layers {
            resources.push(l.as_entire_binding());
        }
        if let Some(i) = &self.scene.iridescence {
            resources.push(i.as_entire_binding());
        }
        if let Some(t) = &self.scene.specular {
            resources.push(t.as_entire_binding());
        }
        if let Some(d) = &self.scene.diffuse_transmission {
            resources.push(d.as_entire_binding());
        }
        if let Some(a) = &self.scene.anisotropy {
            resources.push(a.as_entire_binding());
        }
        if let Some(e) = &self.emitters {
            resources.push(e.as_entire_binding());
        }
        resources.extend(self.environment.iter().map(wgpu::Buffer::as_entire_binding));
        resources.push(self.ray_counter.as_entire_binding());
        if let Some(aov) = &self.film.aov {
            resources.push(aov.as_entire_binding());
        }
        if let (Some(marks), Some(counter)) = (&self.film.converged, &self.converged_counter) {
            resources.push(marks.as_entire_binding());
            resources.push(counter.as_entire_binding());
        }
        let entries = binding_table(self.film.precision(), self.features).bind_entries(resources);
        let bind = self.ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("integrator"),
            layout: &self.kernel.layout,
            entries: &entries,
        });
        Ok((params, bind))
    }

    /// Submits `steps` in one compute pass and one submission, between the timer's timestamps
    /// when timing, and waits for them.
    fn submit_all(&self, steps: &[Step], bind: &wgpu::BindGroup) -> Result<(), GpuError> {
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        {
            let timestamp_writes = self.timer.as_ref().map(|t| wgpu::ComputePassTimestampWrites {
                query_set: &t.queries,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: Some(1),
            });
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("integrator"),
                timestamp_writes,
            });
            for step in steps {
                self.record_step(&mut pass, *step, bind);
            }
        }
        if let Some(t) = &self.timer {
            encoder.resolve_query_set(&t.queries, 0..2, &t.resolve, 0);
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.wait()
    }

    /// Renders `blocks` in order: each block's samples of every pixel still taking samples, then
    /// (with `converge`) the GPU's adaptive-sampling test, in one compute pass and one submission
    /// unless the pass must be stoppable; fits the dispatches to the time they took. Returns the
    /// device seconds when timing.
    fn render_blocks(&mut self, blocks: &[Block]) -> Result<Option<f64>, GpuError> {
        let (slots, steps) = self.plan(blocks);
        let (_params, bind) = self.bind_group(&slots)?;
        // A pass after a long one is split where a cancel flag may stop it, and so is the first
        // when its paths may be long (its dispatches start halved).
        let split = self.cancel.is_some()
            && steps.len() > 1
            && (self.last_pass_seconds > LONG_PASS_SECONDS
                || (self.last_pass_seconds == 0.0 && self.sizing.is_halved()));
        let started = std::time::Instant::now();
        let sample_steps = steps.iter().filter(|s| matches!(s, Step::Samples { .. })).count().max(1);
        let longest = if split {
            Some(self.submit_steps_one_by_one(&steps, &bind)?)
        } else {
            self.submit_all(&steps, &bind)?;
            None
        };
        self.last_pass_seconds = started.elapsed().as_secs_f64().max(f64::MIN_POSITIVE);
        self.sizing.fit(longest.unwrap_or(self.last_pass_seconds / sample_steps as f64));
        if let Some(t) = &mut self.timer {
            t.last = if split { None } else { Some(t.read_seconds(&self.ctx)?) };
        }
        Ok(self.timer.as_ref().and_then(|t| t.last))
    }

    /// The film so far (sums in `f64`, counts, rejected samples), read back.
    pub fn film(&self) -> Result<Film, GpuError> {
        self.film.read(&self.ctx)
    }

    /// Replaces the film (to resume a saved render, or with an empty film to start again).
    pub fn load_film(&mut self, data: &Film) -> Result<(), GpuError> {
        self.film.write(&self.ctx, data)?;
        self.converged = data.converged_count();
        self.write_converged_counter(self.converged.unwrap_or(0))
    }
}
