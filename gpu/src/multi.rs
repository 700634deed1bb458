//! [`MultiGpuRenderer`]: one render on several GPUs of one host at once.
//!
//! Every device holds the whole scene (the BVH is built once on the host, and the scene, BVH,
//! light BVH and environment CDFs packed once, then uploaded to each) and a film of the whole
//! image. Each pass's sample indices `a..b` are cut into
//! consecutive ranges, one per device, in proportion to the devices' weights: equal for
//! devices of one model, else their measured rates. A furnace sampler is addressable — sample
//! `i` of pixel `p` is the same wherever it is traced — so the devices' films add up to the
//! film of one device's render of `a..b`, as the parts of a split render do
//! ([`furnace_render::split`]): the same samples summed in another order, equal to the
//! rounding that [`furnace_render::split::merge_bound`] bounds, not bit for bit.
//!
//! Reading the film ([`Integrator::film`]) collects: each device's film is added to a film
//! kept on the host, then cleared on the device. A device that fails (lost, out of memory)
//! is retired: the samples its film held since the last collection, and its share of the
//! pass, are rendered again by the others, and the render goes on ([`Retirement`] says what
//! happened). Only when every device has failed does a pass fail.
//!
//! Under adaptive sampling the devices do not test their own films (each holds part of a
//! pixel's samples): passes are cut at the test points, and at each the films are collected,
//! the sum tested on the host ([`Film::test_convergence`], the rule of every backend) and its
//! marks given to every device. That costs a read-back of every film every
//! [`furnace_render::ADAPTIVE_STEP`] samples per pixel.

use crate::integrator::PackedScene;
use crate::{GpuContext, GpuError, GpuRenderer};
use furnace_accel::{BuildOptions, Bvh};
use furnace_render::split::SampleRange;
use furnace_render::{ADAPTIVE_STEP, Film, Integrator, RenderError, RenderSettings};
use furnace_sampling::AnySampler;
use furnace_scene::{Camera, Scene};
use std::time::Instant;

/// One render on several devices ([module docs](self)).
#[derive(Debug)]
pub struct MultiGpuRenderer {
    settings: RenderSettings,
    /// The render's sampler, for its index check before any device renders.
    sampler: AnySampler,
    members: Vec<Member>,
    /// The samples collected from the devices, and a film loaded to continue.
    collected: Film,
    /// Equal weights (devices of one model), else weights by measured rate.
    equal: bool,
    /// Devices retired since [`MultiGpuRenderer::take_retirements`] was last called.
    retired: Vec<Retirement>,
    /// How many devices the render began with.
    opened: usize,
    /// Passes rendered so far (for [`MultiGpuRenderer::lose_device_at`]).
    passes: u64,
    /// A device to destroy before a pass: `(index, pass)`.
    fault: Option<(usize, u64)>,
    /// Seconds the shares of passes took from start to the last device's end (what the
    /// render waited), and the seconds spent collecting films, since [`MultiGpuRenderer::reset_load`].
    shares_seconds: f64,
    collect_seconds: f64,
}

/// One device's part in a render on several GPUs since [`MultiGpuRenderer::reset_load`]
/// ([`MultiGpuRenderer::load`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceLoad {
    /// Its position in the list the render was opened with.
    pub index: usize,
    /// Pixel samples it rendered.
    pub pixel_samples: f64,
    /// Seconds it was rendering (its thread's time from its share's start to its end).
    pub busy_seconds: f64,
}

/// How a render on several GPUs spent its time since [`MultiGpuRenderer::reset_load`]: each
/// device's work, the time the passes' shares took (each waits for its slowest device) and the
/// time collecting films on the host.
#[derive(Clone, Debug, PartialEq)]
pub struct Load {
    /// The devices rendering now, in the order they were opened.
    pub devices: Vec<DeviceLoad>,
    /// Seconds from each share's start to its last device's end, summed.
    pub shares_seconds: f64,
    /// Seconds reading back, adding and clearing the devices' films.
    pub collect_seconds: f64,
}

impl DeviceLoad {
    /// Its rate while rendering, in pixel samples per second.
    pub fn rate(&self) -> f64 {
        self.pixel_samples / self.busy_seconds.max(1e-12)
    }
}

impl Load {
    /// The share of the passes' shares' time that device `d` was rendering.
    pub fn busy(&self, d: &DeviceLoad) -> f64 {
        d.busy_seconds / self.shares_seconds.max(1e-12)
    }

    /// The share of the devices' time spent waiting for another device to finish its share:
    /// `1 − Σ busy / (devices × shares_seconds)` (0 with nothing measured).
    pub fn idle(&self) -> f64 {
        let n = self.devices.len() as f64;
        if n == 0.0 || self.shares_seconds <= 0.0 {
            return 0.0;
        }
        let busy: f64 = self.devices.iter().map(|d| d.busy_seconds).sum();
        (1.0 - busy / (n * self.shares_seconds)).max(0.0)
    }
}

/// A device taking part in the render.
#[derive(Debug)]
struct Member {
    /// Its position in the list the render was opened with.
    index: usize,
    renderer: GpuRenderer,
    /// The sample ranges its film holds since the last collection.
    held: Vec<SampleRange>,
    /// Pixel samples per second of its last share (`None` before one is measured).
    rate: Option<f64>,
    /// Its [`DeviceLoad`] figures: pixel samples and busy seconds.
    pixel_samples: f64,
    busy_seconds: f64,
}

/// A device that failed and left the render.
#[derive(Debug)]
pub struct Retirement {
    /// Its position in the list the render was opened with.
    pub index: usize,
    /// Its adapter ([`GpuContext::describe`]).
    pub adapter: String,
    /// Why it left.
    pub error: GpuError,
    /// The sample ranges it had rendered or was rendering, lost with its film, that the other
    /// devices rendered again (empty when it failed while opening).
    pub rerendered: Vec<SampleRange>,
}

impl std::fmt::Display for Retirement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GPU {} ({}) left the render: {}", self.index, self.adapter, self.error)?;
        if !self.rerendered.is_empty() {
            let ranges: Vec<String> = self.rerendered.iter().map(ToString::to_string).collect();
            write!(f, "; the other GPUs rendered its samples {} again", ranges.join(", "))?;
        }
        Ok(())
    }
}

/// Cuts `range` into consecutive parts in proportion to `weights` (equal parts when the weights
/// are not all positive and finite): part `k` starts where part `k − 1` ends, each boundary the
/// rounded cumulative share. A part can be empty (`None`) when the range is shorter than the
/// list.
pub fn split_range(range: SampleRange, weights: &[f64]) -> Vec<Option<SampleRange>> {
    let n = weights.len();
    let usable = n > 0 && weights.iter().all(|w| w.is_finite() && *w > 0.0);
    let w: Vec<f64> = if usable { weights.to_vec() } else { vec![1.0; n] };
    let total: f64 = w.iter().sum();
    let len = f64::from(range.len());
    let mut parts = Vec::with_capacity(n);
    let mut start = range.start;
    let mut cumulative = 0.0;
    for (k, wk) in w.iter().enumerate() {
        cumulative += wk;
        let end = if k + 1 == n {
            range.end
        } else {
            let at = range.start + (len * cumulative / total).round() as u32;
            at.clamp(start, range.end)
        };
        parts.push(SampleRange::new(start, end));
        start = end;
    }
    parts
}

/// Shares in proportion to measured rates, a device not yet measured (`None`) taking the mean of
/// those that are (all equal before any is).
fn weights_by_rate(rates: &[Option<f64>]) -> Vec<f64> {
    let measured: Vec<f64> = rates.iter().flatten().copied().collect();
    let mean = if measured.is_empty() { 1.0 } else { measured.iter().sum::<f64>() / measured.len() as f64 };
    rates.iter().map(|r| r.unwrap_or(mean)).collect()
}

/// Whether two adapters are the same model on the same driver (they then get equal shares).
fn same_model(a: &wgpu::AdapterInfo, b: &wgpu::AdapterInfo) -> bool {
    (a.name.as_str(), a.device_type, a.backend, a.driver.as_str(), a.driver_info.as_str())
        == (b.name.as_str(), b.device_type, b.backend, b.driver.as_str(), b.driver_info.as_str())
}

impl MultiGpuRenderer {
    /// Builds the scene's BVH and packs the scene once, then opens the GPU integrator on every
    /// context (in parallel: each uploads the packed words and builds its pipeline), to render
    /// `scene` through `camera`. A device that fails to open (or whose limits the packed scene
    /// exceeds) is retired ([`MultiGpuRenderer::take_retirements`]) and the
    /// render goes on without it.
    ///
    /// # Errors
    /// The sampler's (a fixed-N sampler without N); [`GpuError::Unsupported`] for no context;
    /// [`GpuError::TooLarge`] for a scene over the largest device's limits; the first device's
    /// error when none opens.
    pub fn new(
        contexts: Vec<GpuContext>,
        scene: &Scene,
        camera: &Camera,
        settings: RenderSettings,
    ) -> Result<Self, GpuError> {
        // Refused before the BVH is built, as GpuRenderer::new does.
        let sampler = crate::integrator::renderable_sampler(scene, &settings)?;
        if contexts.is_empty() {
            return Err(GpuError::Unsupported("no GPU to render on".into()));
        }
        // Packed once, within the largest device's limits (a smaller one that it exceeds is
        // retired), and uploaded by each; the BVH's own copy is dropped first.
        let limit = PackedScene::limit_of(&contexts);
        let packed = if scene.instancing.is_empty() {
            let g = &scene.geometry;
            let bvh = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default());
            PackedScene::new(scene, &bvh, camera, settings, limit)?
        } else {
            PackedScene::instanced(scene, camera, settings, limit)?
        };
        let infos: Vec<wgpu::AdapterInfo> = contexts.iter().map(|c| c.info.clone()).collect();
        let opened = contexts.len();
        let results: Vec<(usize, String, Result<GpuRenderer, GpuError>)> = std::thread::scope(|s| {
            let handles: Vec<_> = contexts
                .into_iter()
                .enumerate()
                .map(|(index, ctx)| {
                    let packed = &packed;
                    s.spawn(move || {
                        let adapter = ctx.describe();
                        (index, adapter, GpuRenderer::with_packed(ctx, packed))
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("a device's upload thread panicked")).collect()
        });
        let mut members = Vec::new();
        let mut retired = Vec::new();
        for (index, adapter, r) in results {
            match r {
                Ok(mut renderer) => {
                    renderer.set_convergence_tests(false);
                    members.push(Member {
                        index,
                        renderer,
                        held: Vec::new(),
                        rate: None,
                        pixel_samples: 0.0,
                        busy_seconds: 0.0,
                    });
                }
                Err(error) => retired.push(Retirement { index, adapter, error, rerendered: Vec::new() }),
            }
        }
        if members.is_empty() {
            return Err(retired.remove(0).error);
        }
        Ok(Self {
            collected: Film::for_settings(&settings),
            settings,
            sampler,
            members,
            equal: infos.windows(2).all(|w| same_model(&w[0], &w[1])),
            retired,
            opened,
            passes: 0,
            fault: None,
            shares_seconds: 0.0,
            collect_seconds: 0.0,
        })
    }

    /// Fault injection, to watch the recovery on real GPUs: destroys device `index` (its
    /// position in the list the render was opened with) just before pass number `pass` (0: the
    /// first) with `wgpu::Device::destroy`, which loses it as a driver reset does. The CLI sets
    /// it from `FURNACE_LOSE_GPU=INDEX@PASS`.
    pub fn lose_device_at(&mut self, index: usize, pass: u64) {
        self.fault = Some((index, pass));
    }

    /// Each device's work and the time spent waiting and collecting since the last
    /// [`reset_load`](Self::reset_load) (or the start): what a benchmark reports.
    pub fn load(&self) -> Load {
        Load {
            devices: self
                .members
                .iter()
                .map(|m| DeviceLoad {
                    index: m.index,
                    pixel_samples: m.pixel_samples,
                    busy_seconds: m.busy_seconds,
                })
                .collect(),
            shares_seconds: self.shares_seconds,
            collect_seconds: self.collect_seconds,
        }
    }

    /// Starts [`load`](Self::load)'s figures again from zero (after a warm-up).
    pub fn reset_load(&mut self) {
        for m in &mut self.members {
            (m.pixel_samples, m.busy_seconds) = (0.0, 0.0);
        }
        (self.shares_seconds, self.collect_seconds) = (0.0, 0.0);
    }

    /// Devices rendering now.
    pub fn device_count(&self) -> usize {
        self.members.len()
    }

    /// How many devices the render was opened with (retired ones included).
    pub fn opened_count(&self) -> usize {
        self.opened
    }

    /// The integrator of each device rendering now, in the order it was opened with.
    pub fn renderers(&self) -> impl Iterator<Item = &GpuRenderer> {
        self.members.iter().map(|m| &m.renderer)
    }

    /// The devices retired since the last call, oldest first: a caller reports them.
    pub fn take_retirements(&mut self) -> Vec<Retirement> {
        std::mem::take(&mut self.retired)
    }

    /// Turns GPU timestamps on or off on every device ([`GpuRenderer::set_timing`]); whether
    /// every device has them.
    pub fn set_timing(&mut self, on: bool) -> bool {
        // Every device is set (no short circuit), then the answers combined.
        let answers: Vec<bool> = self.members.iter_mut().map(|m| m.renderer.set_timing(on)).collect();
        answers.into_iter().all(|a| a)
    }

    /// The weight of each member's share: equal, or its measured rate (members not yet
    /// measured take the mean of those that are).
    fn weights(&self) -> Vec<f64> {
        if self.equal {
            return vec![1.0; self.members.len()];
        }
        weights_by_rate(&self.members.iter().map(|m| m.rate).collect::<Vec<_>>())
    }

    /// Each member's share of `ranges`: every range cut by [`split_range`].
    fn shares(&self, ranges: &[SampleRange]) -> Vec<Vec<SampleRange>> {
        let weights = self.weights();
        let mut work = vec![Vec::new(); self.members.len()];
        for &r in ranges {
            for (k, part) in split_range(r, &weights).into_iter().enumerate() {
                work[k].extend(part);
            }
        }
        work
    }

    /// Renders `work` (ranges per member) on all members at once. A member that fails is
    /// retired, and what its film held and was given is rendered again by the others, until
    /// everything is rendered or no member is left (the last failure is returned then).
    fn render_work(&mut self, mut work: Vec<Vec<SampleRange>>) -> Result<(), GpuError> {
        let pixels = f64::from(self.settings.width) * f64::from(self.settings.height);
        loop {
            let start = Instant::now();
            let results: Vec<Result<f64, GpuError>> = std::thread::scope(|s| {
                let handles: Vec<_> = self
                    .members
                    .iter_mut()
                    .zip(&work)
                    .map(|(m, ranges)| {
                        s.spawn(move || {
                            let start = Instant::now();
                            for r in ranges {
                                m.renderer.render_pass(r.start, r.len())?;
                            }
                            Ok(start.elapsed().as_secs_f64())
                        })
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().expect("a device's render thread panicked")).collect()
            });
            self.shares_seconds += start.elapsed().as_secs_f64();
            let mut orphans = Vec::new();
            // A sampler's error is the caller's (a fixed-N sampler run past N), the same on every
            // device: no device is retired for it, and it is returned once every result is in.
            let mut sampler_error = None;
            let mut k = self.members.len();
            for (result, ranges) in results.into_iter().zip(work).rev() {
                k -= 1;
                match result {
                    Ok(seconds) => {
                        let m = &mut self.members[k];
                        let samples: u32 = ranges.iter().map(SampleRange::len).sum();
                        if samples > 0 && seconds > 0.0 {
                            m.rate = Some(pixels * f64::from(samples) / seconds);
                        }
                        m.pixel_samples += pixels * f64::from(samples);
                        m.busy_seconds += seconds;
                        m.held.extend(ranges);
                    }
                    Err(GpuError::Sampler(e)) => sampler_error = Some(e),
                    Err(error) => orphans.extend(self.retire(k, error, ranges)),
                }
            }
            if let Some(e) = sampler_error {
                return Err(GpuError::Sampler(e));
            }
            if orphans.is_empty() {
                return Ok(());
            }
            self.check_any_left()?;
            orphans.sort();
            work = self.shares(&orphans);
        }
    }

    /// Adds every member's film to the collected film and clears it on the device; a member that
    /// cannot be read is retired and its samples rendered again by the others (then collected).
    fn collect(&mut self) -> Result<(), GpuError> {
        loop {
            let start = Instant::now();
            // Read back in parallel (a 4K film is hundreds of megabytes), added in member order.
            let films: Vec<Result<Option<Film>, GpuError>> = std::thread::scope(|s| {
                let handles: Vec<_> = self
                    .members
                    .iter()
                    .map(|m| s.spawn(move || (!m.held.is_empty()).then(|| m.renderer.film()).transpose()))
                    .collect();
                handles.into_iter().map(|h| h.join().expect("a device's read-back thread panicked")).collect()
            });
            let mut orphans = Vec::new();
            let mut k = 0;
            for film in films {
                let m = &mut self.members[k];
                let read = film.and_then(|f| {
                    let Some(f) = f else { return Ok(()) };
                    self.collected.add_film(&f).map_err(|e| GpuError::Wgpu(e.to_string()))?;
                    m.held.clear();
                    m.renderer.clear_film()?;
                    // Clearing took the marks too: the render's are the collected film's.
                    match self.collected.converged() {
                        Some(marks) => m.renderer.set_converged(marks),
                        None => Ok(()),
                    }
                });
                match read {
                    Ok(()) => k += 1,
                    Err(error) => orphans.extend(self.retire(k, error, Vec::new())),
                }
            }
            self.collect_seconds += start.elapsed().as_secs_f64();
            if orphans.is_empty() {
                return Ok(());
            }
            self.check_any_left()?;
            orphans.sort();
            let work = self.shares(&orphans);
            self.render_work(work)?;
        }
    }

    /// Retires member `k` for `error`: what its film held since the last collection and
    /// `unfinished` (work it was given) are lost with it, recorded in its [`Retirement`] and
    /// returned, sorted, for the others to render again.
    fn retire(&mut self, k: usize, error: GpuError, unfinished: Vec<SampleRange>) -> Vec<SampleRange> {
        let m = self.members.remove(k);
        let mut lost = m.held;
        lost.extend(unfinished);
        lost.sort();
        self.retired.push(Retirement {
            index: m.index,
            adapter: m.renderer.context().describe(),
            error,
            rerendered: lost.clone(),
        });
        lost
    }

    /// [`GpuError::DeviceLost`], naming the last failure, once every member is retired.
    fn check_any_left(&self) -> Result<(), GpuError> {
        if !self.members.is_empty() {
            return Ok(());
        }
        let last = self.retired.last().map(|r| r.error.to_string()).unwrap_or_default();
        Err(GpuError::DeviceLost(format!("every GPU of the render failed (the last: {last})")))
    }

    /// Gives every device the collected film's convergence marks (adaptive sampling; nothing
    /// otherwise). A device that fails is retired: it holds no samples since the collection
    /// that comes before every call, so nothing is rendered again.
    fn share_marks(&mut self) -> Result<(), GpuError> {
        let Some(marks) = self.collected.converged() else { return Ok(()) };
        let failed: Vec<(usize, GpuError)> = (self.members.iter_mut().enumerate())
            .filter_map(|(k, m)| m.renderer.set_converged(marks).err().map(|e| (k, e)))
            .collect();
        for (k, error) in failed.into_iter().rev() {
            self.retire(k, error, Vec::new());
        }
        self.check_any_left()
    }
}

impl Integrator for MultiGpuRenderer {
    fn name(&self) -> &'static str {
        "gpus"
    }

    /// `gpus: ` and each device's adapter, in order (`N × adapter` for one model).
    fn describe(&self) -> String {
        let names: Vec<String> = self.members.iter().map(|m| m.renderer.context().describe()).collect();
        match names.first() {
            Some(first) if names.iter().all(|n| n == first) => format!("gpus: {} × {first}", names.len()),
            _ => format!("gpus: {}", names.join(" + ")),
        }
    }

    fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The pass cut into one share per device ([`split_range`]), rendered on all at once.
    fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), RenderError> {
        if samples_per_pixel == 0 || self.settings.width == 0 || self.settings.height == 0 {
            return Ok(());
        }
        self.sampler.check_index(first_sample.saturating_add(samples_per_pixel - 1))?;
        let Some(range) = SampleRange::new(first_sample, first_sample.saturating_add(samples_per_pixel))
        else {
            return Ok(());
        };
        if let Some((index, pass)) = self.fault
            && pass == self.passes
            && let Some(m) = self.members.iter().find(|m| m.index == index)
        {
            m.renderer.context().device.destroy();
        }
        self.passes += 1;
        let Some(rule) = self.settings.adaptive else {
            let work = self.shares(&[range]);
            return Ok(self.render_work(work)?);
        };
        // Adaptive sampling: blocks that end at the multiples of ADAPTIVE_STEP, each shared, then
        // the sum of the films tested where the rule tests and the marks given to every device.
        let mut block = range.start;
        while block < range.end {
            let block_end = (block / ADAPTIVE_STEP + 1).saturating_mul(ADAPTIVE_STEP).min(range.end);
            let Some(r) = SampleRange::new(block, block_end) else { break };
            let work = self.shares(&[r]);
            self.render_work(work)?;
            if rule.tests_at(block_end) {
                self.collect()?;
                self.collected.test_convergence(&rule);
                self.share_marks()?;
            }
            block = block_end;
        }
        Ok(())
    }

    /// Collects every device's film into the host's ([module docs](self)) and returns it.
    fn film(&mut self) -> Result<Film, RenderError> {
        self.collect()?;
        Ok(self.collected.clone())
    }

    /// Keeps `film` on the host as the samples collected so far and clears every device's film.
    fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
        RenderError::check_film(film, &self.settings)?;
        for m in &mut self.members {
            m.renderer.clear_film()?;
            m.held.clear();
        }
        self.collected = film.clone();
        Ok(self.share_marks()?)
    }

    /// The sum of the devices' own pass sizes: each device's share is about its own pass.
    fn pass_samples(&self) -> u32 {
        self.members.iter().map(|m| Integrator::pass_samples(&m.renderer)).sum::<u32>().max(1)
    }

    /// The slowest device's time of the last pass (the pass waits for it), where every device
    /// measures it.
    fn last_pass_device_seconds(&self) -> Option<f64> {
        self.members
            .iter()
            .map(|m| m.renderer.last_pass_gpu_seconds())
            .try_fold(0.0f64, |a, s| s.map(|s| a.max(s)))
    }

    /// The collected film's count: the marks change only at a test, which collects first.
    fn converged_pixels(&self) -> Option<u64> {
        self.collected.converged_count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(a: u32, b: u32) -> SampleRange {
        SampleRange::new(a, b).unwrap()
    }

    #[test]
    fn idle_is_the_devices_wait_for_the_slowest() {
        let d = |busy_seconds| DeviceLoad { index: 0, pixel_samples: 1.0, busy_seconds };
        // Shares of 2 s in all: one device busy throughout, one for 1.5 s: a quarter of its time,
        // an eighth of the two's, waiting.
        let load = Load { devices: vec![d(2.0), d(1.5)], shares_seconds: 2.0, collect_seconds: 0.0 };
        assert!((load.idle() - 0.125).abs() < 1e-12);
        assert_eq!(Load { devices: vec![], shares_seconds: 1.0, collect_seconds: 0.0 }.idle(), 0.0);
        assert_eq!(Load { devices: vec![d(0.0)], shares_seconds: 0.0, collect_seconds: 0.0 }.idle(), 0.0);
    }

    #[test]
    fn unmeasured_devices_take_the_mean_rate() {
        assert_eq!(weights_by_rate(&[None, None]), [1.0, 1.0]);
        assert_eq!(weights_by_rate(&[Some(3.0), None, Some(1.0)]), [3.0, 2.0, 1.0]);
        // A fast device and a slow one: a pass of 8 samples goes 6 and 2.
        let w = weights_by_rate(&[Some(300.0), Some(100.0)]);
        assert_eq!(split_range(r(0, 8), &w), [Some(r(0, 6)), Some(r(6, 8))]);
    }

    #[test]
    fn ranges_split_in_proportion_and_tile() {
        assert_eq!(split_range(r(0, 8), &[1.0, 1.0]), [Some(r(0, 4)), Some(r(4, 8))]);
        assert_eq!(
            split_range(r(10, 13), &[1.0, 1.0, 1.0, 1.0]),
            [Some(r(10, 11)), Some(r(11, 12)), None, Some(r(12, 13))],
            "boundaries at 10 + 0.75, 1.5, 2.25 rounded"
        );
        assert_eq!(split_range(r(0, 10), &[3.0, 1.0]), [Some(r(0, 8)), Some(r(8, 10))]);
        // Unusable weights: equal parts.
        assert_eq!(split_range(r(0, 4), &[f64::NAN, 1.0]), [Some(r(0, 2)), Some(r(2, 4))]);
        assert_eq!(split_range(r(0, 4), &[0.0, 1.0]), [Some(r(0, 2)), Some(r(2, 4))]);
        // Every split tiles its range, whatever the weights.
        for weights in [&[1.0][..], &[1.0, 2.0, 3.0], &[1e-9, 1.0, 1e9], &[5.0; 8]] {
            for (a, b) in [(0, 1), (3, 4), (0, 7), (100, 1000), (0, u32::MAX)] {
                let parts = split_range(r(a, b), weights);
                assert_eq!(parts.len(), weights.len());
                let mut at = a;
                for p in parts.into_iter().flatten() {
                    assert_eq!(p.start, at, "{weights:?} {a}..{b}");
                    at = p.end;
                }
                assert_eq!(at, b, "{weights:?} {a}..{b}");
            }
        }
    }
}
