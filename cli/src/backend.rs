//! Which integrator renders: `--backend auto|cpu|gpu` and `--adapter`, decided in one place
//! ([`open`]) for `furnace render`, `chart`, `bench` and the tests; `--gpus` ([`open_gpus`])
//! for one render on several GPUs.

use furnace_accel::SceneAccel;
use furnace_cpu::CpuRenderer;
use furnace_gpu::{AdapterChoice, GpuContext, GpuError, GpuRenderer, MultiGpuRenderer};
use furnace_render::{CancelFlag, Film, Integrator, RenderError, RenderSettings};
use furnace_scene::{Camera, Scene};
use std::sync::Arc;

/// Where to render (`--backend`; the value's help is what the command line lists).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum BackendChoice {
    /// The CPU reference integrator.
    #[value(help = "The CPU reference integrator (rayon)")]
    Cpu,
    /// The wgpu integrator on the best adapter (or the adapter named), software ones included.
    #[value(help = "The wgpu integrator")]
    Gpu,
    /// A hardware GPU if there is one (or the adapter named), else the CPU: software adapters
    /// are slower than the CPU integrator and used only when asked for.
    #[default]
    #[value(help = "A hardware GPU if present, else the CPU")]
    Auto,
}

/// The GPU context `choice` and `adapter` ask for: `None` for the CPU.
///
/// # Errors
/// [`GpuError::NoAdapter`] when a GPU is required (`Gpu`, or an adapter named) and none is
/// found; other device errors.
pub fn gpu_context(choice: BackendChoice, adapter: Option<&str>) -> Result<Option<GpuContext>, GpuError> {
    Ok(match (choice, adapter) {
        (BackendChoice::Cpu, _) => None,
        (BackendChoice::Gpu | BackendChoice::Auto, Some(name)) => {
            Some(GpuContext::new(&AdapterChoice::Named(name.to_string()))?)
        }
        (BackendChoice::Gpu, None) => Some(GpuContext::new(&AdapterChoice::Best)?),
        // auto: a hardware adapter if there is one; without, the CPU integrator.
        (BackendChoice::Auto, None) => GpuContext::new(&AdapterChoice::Hardware).ok(),
    })
}

/// `--gpus`: the adapters that render one image together.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GpuSet {
    /// Every hardware adapter (every adapter where there is none, as software ones are then
    /// all there is).
    All,
    /// Adapters as `--adapter` names them: an index, a PCI address, or a part of a name, which
    /// takes every adapter whose name contains it (`NVIDIA`: all of them).
    List(Vec<String>),
}

impl std::str::FromStr for GpuSet {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("all") {
            return Ok(Self::All);
        }
        let entries: Vec<String> = s.split(',').map(|e| e.trim().to_string()).collect();
        if entries.iter().any(String::is_empty) {
            return Err(format!(
                "'{s}' is not a list of GPUs: give `all`, or adapters separated by commas (indices, \
                 PCI addresses or parts of names, as --adapter takes them), e.g. 0,1"
            ));
        }
        Ok(Self::List(entries))
    }
}

/// The indices (in [`GpuContext::adapters`]' order, which `--adapter INDEX` uses) of the adapters
/// `set` names, in its order; an adapter named twice is listed twice.
///
/// # Errors
/// [`GpuError::NoAdapter`] for no adapter at all, or an entry that names none (with the list of
/// adapters present).
pub fn gpu_indices(set: &GpuSet) -> Result<Vec<usize>, GpuError> {
    let adapters = GpuContext::adapters();
    let indices: Vec<usize> = match set {
        GpuSet::All => {
            let hardware: Vec<usize> =
                (0..adapters.len()).filter(|&i| furnace_gpu::context::is_hardware(&adapters[i])).collect();
            if hardware.is_empty() { (0..adapters.len()).collect() } else { hardware }
        }
        GpuSet::List(entries) => {
            let mut v = Vec::new();
            for entry in entries {
                let matched: Vec<usize> = match (entry.parse::<usize>(), furnace_gpu::pci_address(entry)) {
                    (Ok(i), _) => (i < adapters.len()).then_some(i).into_iter().collect(),
                    (_, Some(bus)) => (0..adapters.len())
                        .filter(|&i| furnace_gpu::pci_address(&adapters[i].device_pci_bus_id) == Some(bus))
                        .collect(),
                    _ => {
                        let n = entry.to_lowercase();
                        (0..adapters.len())
                            .filter(|&i| adapters[i].name.to_lowercase().contains(&n))
                            .collect()
                    }
                };
                if matched.is_empty() {
                    return Err(furnace_gpu::context::no_adapter(
                        &format!(" matching \"{entry}\""),
                        &adapters,
                    ));
                }
                v.extend(matched);
            }
            v
        }
    };
    if indices.is_empty() {
        return Err(furnace_gpu::context::no_adapter("", &adapters));
    }
    Ok(indices)
}

/// Opens the GPU integrator on the adapters at `indices` ([`gpu_indices`]): the plain one for a
/// single adapter, [`MultiGpuRenderer`] for several (a device on each, the BVH built once).
///
/// # Errors
/// As [`open`]; among several, an adapter that refuses a device (said on stderr) or a device
/// that fails to take the scene ([`MultiGpuRenderer::take_retirements`]) is left out, an error
/// only when none opens.
pub fn open_gpus(
    indices: &[usize],
    scene: Arc<Scene>,
    camera: &Camera,
    settings: RenderSettings,
    accel: Option<SceneAccel>,
) -> Result<Backend, RenderError> {
    if let [one] = indices {
        if std::env::var_os("FURNACE_LOSE_GPU").is_some() {
            eprintln!("warning: FURNACE_LOSE_GPU is ignored: it loses a device of a render on several GPUs");
        }
        return open(BackendChoice::Gpu, Some(&one.to_string()), scene, camera, settings, accel);
    }
    // Several devices pack the scene once from a BVH of their own: the probe's is freed first.
    drop(accel);
    let fault = lose_gpu_from_env()?;
    // An adapter that refuses a device is left out, as one that fails later would be.
    let mut contexts = Vec::new();
    let mut first_error = None;
    for i in indices {
        match GpuContext::new(&AdapterChoice::Named(i.to_string())) {
            Ok(ctx) => contexts.push(ctx),
            Err(e) => {
                eprintln!("warning: adapter {i} could not be opened, rendering without it: {e}");
                first_error.get_or_insert(e);
            }
        }
    }
    if let (true, Some(e)) = (contexts.is_empty(), first_error) {
        return Err(e.into());
    }
    let mut multi = MultiGpuRenderer::new(contexts, &scene, camera, settings)?;
    if let Some((index, pass)) = fault {
        multi.lose_device_at(index, pass);
    }
    Ok(Backend::Gpus(Box::new(multi)))
}

/// `FURNACE_LOSE_GPU=INDEX@PASS`: a render on several GPUs destroys device INDEX (its position
/// in `--gpus`) before pass PASS (0: the first), to watch the recovery on real GPUs
/// ([`MultiGpuRenderer::lose_device_at`]).
fn lose_gpu_from_env() -> Result<Option<(usize, u64)>, GpuError> {
    let Ok(v) = std::env::var("FURNACE_LOSE_GPU") else { return Ok(None) };
    let parsed = v.split_once('@').and_then(|(k, p)| Some((k.trim().parse().ok()?, p.trim().parse().ok()?)));
    parsed.map(Some).ok_or_else(|| {
        GpuError::Unsupported(format!(
            "FURNACE_LOSE_GPU={v}: expected INDEX@PASS (the device's position in --gpus, the pass \
             before which it is lost), e.g. 1@10"
        ))
    })
}

/// The integrator a command's `--backend`, `--adapter` and `--gpus` ask for: [`open_gpus`] with
/// `--gpus` (warning on stderr of an adapter listed twice: two devices then share one GPU,
/// which tests use, but renders no faster), else [`open`].
///
/// # Errors
/// `--gpus` with `--backend cpu`; [`gpu_indices`]'s and [`open`]'s errors, as text.
pub fn open_chosen(
    choice: BackendChoice,
    adapter: Option<&str>,
    gpus: Option<&GpuSet>,
    scene: Arc<Scene>,
    camera: &Camera,
    settings: RenderSettings,
    accel: Option<SceneAccel>,
) -> Result<Backend, String> {
    let Some(set) = gpus else {
        return open(choice, adapter, scene, camera, settings, accel).map_err(|e| e.to_string());
    };
    if choice == BackendChoice::Cpu {
        return Err("--gpus renders on GPUs: it cannot be combined with --backend cpu".into());
    }
    let indices = gpu_indices(set).map_err(|e| e.to_string())?;
    for (k, i) in indices.iter().enumerate() {
        if indices[..k].contains(i) {
            eprintln!(
                "warning: --gpus names adapter {i} more than once: its devices share one GPU, which \
                 runs them in turn (slower than one device)"
            );
        }
    }
    let mut backend = open_gpus(&indices, scene, camera, settings, accel).map_err(|e| e.to_string())?;
    for line in backend.take_retirements() {
        eprintln!("warning: {line}");
    }
    Ok(backend)
}

/// An open integrator: the CPU reference or the wgpu one, as [`gpu_context`] decides, or the
/// wgpu one on several GPUs ([`open_gpus`]).
#[derive(Debug)]
pub enum Backend {
    /// The CPU reference integrator.
    Cpu(Box<CpuRenderer>),
    /// The wgpu integrator.
    Gpu(Box<GpuRenderer>),
    /// The wgpu integrator on several devices.
    Gpus(Box<MultiGpuRenderer>),
}

/// Whether [`open`] on `choice` may take the structure [`CpuRenderer::accel_for`] builds for
/// `scene`: the CPU integrator takes any, the GPU one a single BVH only (an instanced scene's GPU
/// layout is its own). With [`BackendChoice::Auto`] the device is not known yet: a scene
/// without instances is worth building for either.
pub fn takes_prebuilt(choice: BackendChoice, scene: &Scene) -> bool {
    choice == BackendChoice::Cpu || scene.instancing.is_empty()
}

/// Opens the integrator that `choice` and `adapter` ask for on `scene` seen through `camera`,
/// with an empty film. `accel`, the scene's structure as [`CpuRenderer::accel_for`] builds it
/// (by the default light's probe, `env::apply` of the binary), is taken instead of building it
/// again: by the CPU integrator always, by the GPU one when it is one BVH (an instanced scene's
/// GPU layout differs, and is built anew).
///
/// # Errors
/// The GPU's ([`gpu_context`], upload, pipeline) and the sampler's (a fixed-N sampler without
/// N), as [`RenderError`]s.
pub fn open(
    choice: BackendChoice,
    adapter: Option<&str>,
    scene: Arc<Scene>,
    camera: &Camera,
    settings: RenderSettings,
    accel: Option<SceneAccel>,
) -> Result<Backend, RenderError> {
    match (gpu_context(choice, adapter)?, accel) {
        (Some(ctx), accel) => Ok(Backend::Gpu(Box::new(gpu_renderer(ctx, &scene, camera, settings, accel)?))),
        (None, Some(accel)) => {
            Ok(Backend::Cpu(Box::new(CpuRenderer::with_accel(scene, camera, settings, accel)?)))
        }
        (None, None) => Ok(Backend::Cpu(Box::new(CpuRenderer::new(scene, camera, settings)?))),
    }
}

/// The GPU integrator on `ctx`, taking `accel` where it is the scene's one BVH
/// ([`takes_prebuilt`]) and building its own structure otherwise.
///
/// # Errors
/// The GPU's (upload, pipeline) and the sampler's.
pub fn gpu_renderer(
    ctx: GpuContext,
    scene: &Scene,
    camera: &Camera,
    settings: RenderSettings,
    accel: Option<SceneAccel>,
) -> Result<GpuRenderer, GpuError> {
    match accel {
        Some(SceneAccel::Flat(bvh)) if takes_prebuilt(BackendChoice::Gpu, scene) => {
            GpuRenderer::with_bvh(ctx, scene, &bvh, camera, settings)
        }
        accel => {
            drop(accel);
            GpuRenderer::new(ctx, scene, camera, settings)
        }
    }
}

impl Backend {
    /// The integrator.
    pub fn integrator(&mut self) -> &mut dyn Integrator {
        match self {
            Self::Cpu(c) => c.as_mut(),
            Self::Gpu(g) => g.as_mut(),
            Self::Gpus(g) => g.as_mut(),
        }
    }

    /// The integrator, shared.
    pub fn integrator_ref(&self) -> &dyn Integrator {
        match self {
            Self::Cpu(c) => c.as_ref(),
            Self::Gpu(g) => g.as_ref(),
            Self::Gpus(g) => g.as_ref(),
        }
    }

    /// The wgpu integrator, if that is what this is (benchmarks read its counters).
    pub fn gpu(&mut self) -> Option<&mut GpuRenderer> {
        match self {
            Self::Gpu(g) => Some(g),
            Self::Cpu(_) | Self::Gpus(_) => None,
        }
    }

    /// The devices that left a render on several GPUs since the last call, each said on one
    /// line; empty for the other backends.
    pub fn take_retirements(&mut self) -> Vec<String> {
        match self {
            Self::Gpus(g) => g.take_retirements().iter().map(ToString::to_string).collect(),
            Self::Cpu(_) | Self::Gpu(_) => Vec::new(),
        }
    }
}

impl Integrator for Backend {
    fn name(&self) -> &'static str {
        self.integrator_ref().name()
    }

    fn describe(&self) -> String {
        self.integrator_ref().describe()
    }

    fn settings(&self) -> &RenderSettings {
        self.integrator_ref().settings()
    }

    /// The integrator's pass; a device that left a render on several GPUs is reported on
    /// stderr as it happens (the render goes on without it).
    fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), RenderError> {
        let result = self.integrator().render_pass(first_sample, samples_per_pixel);
        for line in self.take_retirements() {
            eprintln!("warning: {line}");
        }
        result
    }

    /// The integrator's film; as for a pass, a device that left is reported on stderr.
    fn film(&mut self) -> Result<Film, RenderError> {
        let result = self.integrator().film();
        for line in self.take_retirements() {
            eprintln!("warning: {line}");
        }
        result
    }

    fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
        self.integrator().set_film(film)
    }

    fn pass_samples(&self) -> u32 {
        self.integrator_ref().pass_samples()
    }

    fn last_pass_device_seconds(&self) -> Option<f64> {
        self.integrator_ref().last_pass_device_seconds()
    }

    fn converged_pixels(&self) -> Option<u64> {
        self.integrator_ref().converged_pixels()
    }

    fn set_cancel_flag(&mut self, flag: CancelFlag) {
        self.integrator().set_cancel_flag(flag);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_scene::builtin;

    fn cpu() -> Backend {
        let settings = RenderSettings { width: 8, height: 8, russian_roulette: true, ..Default::default() };
        let scene = builtin::cornell_box().unwrap();
        let camera = scene.default_camera();
        open(BackendChoice::Cpu, None, Arc::new(scene), &camera, settings, None).unwrap()
    }

    /// The film's bits: sums, counts and rejections (`==` on `f64` would let −0 equal +0).
    fn bits(film: &Film) -> (Vec<u64>, Vec<u64>, u64) {
        let sums = film.sums().iter().flat_map(|s| s.to_array().map(f64::to_bits)).collect();
        (sums, film.counts().to_vec(), film.rejected())
    }

    /// Renders passes of the given sizes from index 0 and returns the film.
    fn passes(backend: &mut Backend, sizes: &[u32]) -> Film {
        let mut first = 0;
        for &n in sizes {
            backend.render_pass(first, n).unwrap();
            first += n;
        }
        backend.film().unwrap()
    }

    #[test]
    fn pass_boundaries_do_not_change_the_film() {
        let whole = passes(&mut cpu(), &[6]);
        assert!(whole.counts().iter().all(|&c| c == 6), "no sample of the Cornell box is rejected");
        for sizes in [&[1, 5][..], &[5, 1], &[2, 2, 2], &[1, 1, 1, 1, 1, 1]] {
            assert_eq!(bits(&passes(&mut cpu(), sizes)), bits(&whole), "{sizes:?}");
        }
    }

    #[test]
    fn a_restored_film_continues_exactly() {
        let whole = passes(&mut cpu(), &[6]);
        let half = passes(&mut cpu(), &[3]);
        let restored =
            Film::from_parts(8, 8, half.sums().to_vec(), half.counts().to_vec(), half.rejected()).unwrap();
        let mut backend = cpu();
        backend.set_film(&restored).unwrap();
        backend.render_pass(3, 3).unwrap();
        assert_eq!(bits(&backend.film().unwrap()), bits(&whole));
        assert!(backend.set_film(&Film::new(4, 4)).is_err(), "a film of another size");
    }
}
