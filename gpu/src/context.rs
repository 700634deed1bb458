//! [`GpuContext`]: an adapter chosen on purpose, a device with the limits it offers, and errors
//! that say what went wrong.

use std::sync::{Arc, Mutex};

/// Errors of the GPU backend: each says what failed and, where it can, what to do.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all (no Vulkan/Metal/DX12 driver, or none matching `--adapter`).
    #[error("no GPU adapter found{0}")]
    NoAdapter(String),
    /// The adapter refused the device (missing feature, limits).
    #[error("could not open a device on {adapter}: {reason}")]
    RequestDevice {
        /// The adapter's name.
        adapter: String,
        /// What wgpu said.
        reason: String,
    },
    /// A validation or out-of-memory error raised by wgpu.
    #[error("GPU error: {0}")]
    Wgpu(String),
    /// The device was lost (driver reset, watchdog, unplugged).
    #[error("the GPU device was lost: {0}")]
    DeviceLost(String),
    /// A buffer larger than the adapter allows.
    #[error("{what} needs {bytes} bytes, more than this adapter's limit of {limit} bytes per buffer")]
    TooLarge {
        /// What the buffer holds.
        what: String,
        /// Bytes needed.
        bytes: u64,
        /// The adapter's limit.
        limit: u64,
    },
    /// A render that needs more memory than the device has room for, found before anything is
    /// allocated ([`crate::memory::check_fits`]).
    #[error(
        "the render needs {} of GPU memory, more than the {} there is room for ({detail}): render it on the CPU, \
         or with fewer triangles or a smaller film",
        crate::memory::gib(*needed),
        crate::memory::gib(*available)
    )]
    OutOfDeviceMemory {
        /// Bytes the render would allocate.
        needed: u64,
        /// Bytes there is room for.
        available: u64,
        /// The largest parts and the device's memory, in words.
        detail: String,
    },
    /// Something in the scene this integrator does not render.
    #[error("{0}")]
    Unsupported(String),
    /// The sampler's: a fixed-N sampler without N, or run past N (nothing was rendered).
    #[error(transparent)]
    Sampler(#[from] furnace_sampling::SamplerError),
    /// A film of another size than the render's.
    #[error("a {film_width}×{film_height} film cannot be loaded into a {width}×{height} render")]
    FilmSize {
        /// The film's width.
        film_width: u32,
        /// The film's height.
        film_height: u32,
        /// The render's width.
        width: u32,
        /// The render's height.
        height: u32,
    },
    /// A film with AOVs for a render without them, or the other way round
    /// ([`furnace_render::RenderError::FilmAovs`]).
    #[error("{}", furnace_render::RenderError::FilmAovs { film_has_aovs: *film_has_aovs })]
    FilmAovs {
        /// Whether the film has AOVs.
        film_has_aovs: bool,
    },
    /// The pass was stopped by its cancel flag ([`furnace_render::RenderError::Interrupted`]):
    /// the film holds its first `samples` samples per pixel and nothing of the rest.
    #[error("interrupted after {samples} samples per pixel of the pass")]
    Interrupted {
        /// Samples per pixel of the pass that the film holds.
        samples: u32,
    },
    /// A film with adaptive-sampling state for a render without it, or the other way round
    /// ([`furnace_render::RenderError::FilmAdaptive`]).
    #[error("{}", furnace_render::RenderError::FilmAdaptive { film_has_state: *film_has_state })]
    FilmAdaptive {
        /// Whether the film has adaptive-sampling state.
        film_has_state: bool,
    },
}

impl From<GpuError> for furnace_render::RenderError {
    fn from(e: GpuError) -> Self {
        match e {
            GpuError::Sampler(e) => Self::Sampler(e),
            GpuError::FilmSize { film_width, film_height, width, height } => {
                Self::FilmSize { film_width, film_height, width, height }
            }
            GpuError::FilmAovs { film_has_aovs } => Self::FilmAovs { film_has_aovs },
            GpuError::FilmAdaptive { film_has_state } => Self::FilmAdaptive { film_has_state },
            GpuError::Interrupted { samples } => Self::Interrupted { samples },
            e => Self::Device(Box::new(e)),
        }
    }
}

/// Which adapter to use.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum AdapterChoice {
    /// The best one: a discrete GPU, else integrated, else virtual, else a software one
    /// (Mesa's software Vulkan, WARP).
    #[default]
    Best,
    /// Only a hardware adapter (discrete, integrated or virtual); `None` is an error.
    Hardware,
    /// The first adapter whose name contains this text (case-insensitive), or whose index in
    /// [`GpuContext::adapters`] it is.
    Named(String),
}

/// An open device and what it can do.
#[derive(Debug)]
pub struct GpuContext {
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Name, backend, driver, device type.
    pub info: wgpu::AdapterInfo,
    /// Whether shaders may use `f64` ([`wgpu::Features::SHADER_F64`]).
    pub shader_f64: bool,
    /// Errors raised asynchronously (uncaptured validation / OOM errors), drained by
    /// [`GpuContext::check`].
    errors: Arc<Mutex<Vec<GpuError>>>,
    /// Why the device was lost, once it is: reported by every later [`GpuContext::check`]
    /// (a lost device stays lost; the validation errors that follow are its consequences).
    lost: Arc<Mutex<Option<String>>>,
}

/// The adapters of Vulkan, Metal and DX12 — the backends furnace supports (`WGPU_BACKEND`
/// chooses others). Not OpenGL: wgpu would fall back to Mesa's GL llvmpipe where no Vulkan
/// driver is installed (far slower than Mesa's software Vulkan, and chosen silently), and
/// probing GL on a headless machine prints driver noise on stderr.
///
/// One instance per process, shared by every context (and by a viewer's window surface, which
/// must come from the instance of the device that draws into it): NVIDIA's Vulkan driver finds no adapter
/// once about 30 instances have been created and dropped in a process, and a `furnace chart`
/// study makes a renderer per configuration and checkpoint (a test opens forty).
pub fn instance() -> &'static wgpu::Instance {
    static INSTANCE: std::sync::OnceLock<wgpu::Instance> = std::sync::OnceLock::new();
    INSTANCE.get_or_init(|| {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        if std::env::var_os("WGPU_BACKEND").is_none() {
            desc.backends = wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12;
        }
        wgpu::Instance::new(desc)
    })
}

/// Preference order of device types (lower is better).
fn rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

/// A PCI address `[DOMAIN:]BUS:DEVICE.FUNCTION` in hex (`0000:18:00.0`, nvidia-smi's
/// `00000000:18:00.0`, `18:00.0`), as `(domain, bus, device, function)`; `None` if `s` is not one.
/// How a job on a host with several GPUs names the one its scheduler gave it
/// (`nvidia-smi --query-gpu=pci.bus_id`): Vulkan does not read `CUDA_VISIBLE_DEVICES`.
pub fn pci_address(s: &str) -> Option<(u32, u32, u32, u32)> {
    let s = s.trim();
    let (rest, function) = s.rsplit_once('.')?;
    let mut fields: Vec<&str> = rest.split(':').collect();
    if fields.len() == 2 {
        fields.insert(0, "0");
    }
    let [domain, bus, device] = fields[..] else { return None };
    let hex = |v: &str| (!v.is_empty() && v.len() <= 8).then(|| u32::from_str_radix(v, 16).ok()).flatten();
    Some((hex(domain)?, hex(bus)?, hex(device)?, hex(function)?))
}

/// Whether an adapter runs on real GPU hardware.
pub fn is_hardware(info: &wgpu::AdapterInfo) -> bool {
    matches!(
        info.device_type,
        wgpu::DeviceType::DiscreteGpu | wgpu::DeviceType::IntegratedGpu | wgpu::DeviceType::VirtualGpu
    )
}

/// [`GpuError::NoAdapter`] for a search described by `what` (empty, or e.g. ` matching "NVIDIA"`)
/// among `adapters` (in [`GpuContext::adapters`]' order): it lists them with their indices and PCI
/// addresses, or says how to install a driver when there is none.
pub fn no_adapter(what: &str, adapters: &[wgpu::AdapterInfo]) -> GpuError {
    if adapters.is_empty() {
        return GpuError::NoAdapter(format!(
            "{what}; install a Vulkan driver (e.g. Mesa's mesa-vulkan-drivers for the lavapipe software device)"
        ));
    }
    let names: Vec<String> = adapters
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let bus = if a.device_pci_bus_id.is_empty() {
                String::new()
            } else {
                format!(", PCI {}", a.device_pci_bus_id)
            };
            format!("{i}: {} ({:?}, {:?}{bus})", a.name, a.device_type, a.backend)
        })
        .collect();
    GpuError::NoAdapter(format!("{what}; adapters present: {}", names.join(", ")))
}

impl GpuContext {
    /// The adapters present, best first (see [`AdapterChoice::Best`]).
    pub fn adapters() -> Vec<wgpu::AdapterInfo> {
        let mut v: Vec<_> = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::all()))
            .iter()
            .map(|a| a.get_info())
            .collect();
        v.sort_by_key(|i| rank(i.device_type));
        v
    }

    /// Picks an adapter and opens a device with every limit the adapter offers and
    /// `SHADER_F64` / `TIMESTAMP_QUERY` when available.
    pub fn new(choice: &AdapterChoice) -> Result<Self, GpuError> {
        let instance = instance();
        let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        adapters.sort_by_key(|a| rank(a.get_info().device_type));
        let picked = match choice {
            AdapterChoice::Best => adapters.first(),
            AdapterChoice::Hardware => adapters.iter().find(|a| is_hardware(&a.get_info())),
            AdapterChoice::Named(name) => match (name.parse::<usize>(), pci_address(name)) {
                (Ok(i), _) => adapters.get(i),
                (_, Some(bus)) => {
                    adapters.iter().find(|a| pci_address(&a.get_info().device_pci_bus_id) == Some(bus))
                }
                _ => {
                    let n = name.to_lowercase();
                    adapters.iter().find(|a| a.get_info().name.to_lowercase().contains(&n))
                }
            },
        };
        let Some(adapter) = picked.cloned() else {
            let what = match choice {
                AdapterChoice::Best => String::new(),
                AdapterChoice::Hardware => {
                    " (hardware only: software adapters such as lavapipe excluded)".into()
                }
                AdapterChoice::Named(n) => format!(" matching \"{n}\""),
            };
            let infos: Vec<wgpu::AdapterInfo> = adapters.iter().map(wgpu::Adapter::get_info).collect();
            return Err(no_adapter(&what, &infos));
        };
        let info = adapter.get_info();
        let offered = adapter.features();
        let wanted = wgpu::Features::SHADER_F64 | wgpu::Features::TIMESTAMP_QUERY;
        let required_features = offered & wanted;
        let desc = wgpu::DeviceDescriptor {
            label: Some("furnace"),
            required_features,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|e| GpuError::RequestDevice { adapter: info.name.clone(), reason: e.to_string() })?;
        let errors: Arc<Mutex<Vec<GpuError>>> = Arc::default();
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(GpuError::Wgpu(e.to_string()));
            }
        }));
        let lost: Arc<Mutex<Option<String>>> = Arc::default();
        let sink = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            let mut v = sink.lock().unwrap_or_else(|p| p.into_inner());
            v.get_or_insert_with(|| {
                if message.is_empty() { format!("{reason:?}") } else { format!("{reason:?}: {message}") }
            });
        });
        Ok(Self {
            shader_f64: required_features.contains(wgpu::Features::SHADER_F64),
            adapter,
            device,
            queue,
            info,
            errors,
            lost,
        })
    }

    /// [`GpuError::DeviceLost`] once the device is lost (on this and every later call: the
    /// errors queued since are dropped, they are the loss's consequences); otherwise the first
    /// error raised since the last call (validation, out of memory), if any, the others raised
    /// since being dropped.
    pub fn check(&self) -> Result<(), GpuError> {
        let mut v = self.errors.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(reason) = self.lost.lock().unwrap_or_else(|p| p.into_inner()).as_ref() {
            v.clear();
            return Err(GpuError::DeviceLost(reason.clone()));
        }
        // The first error; those after it are usually its consequences (an allocation that
        // failed leaves an invalid buffer that every later command using it reports): dropped,
        // so that they are not blamed on the next, unrelated call.
        let first = if v.is_empty() { Ok(()) } else { Err(v.remove(0)) };
        v.clear();
        first
    }

    /// A buffer holding `contents` (padded with zeros to a multiple of 4 bytes), `COPY_DST` added
    /// to `usage`. Unlike `wgpu::util::DeviceExt::create_buffer_init`, which panics when the
    /// device is lost (its buffer cannot be mapped at creation), a lost device or failed
    /// allocation is an `Err` here, at once if already known, else from the next
    /// [`GpuContext::check`] / [`GpuContext::wait`].
    pub fn buffer_init(
        &self,
        label: &str,
        contents: &[u8],
        usage: wgpu::BufferUsages,
    ) -> Result<wgpu::Buffer, GpuError> {
        self.check()?;
        let size = (contents.len() as u64).div_ceil(wgpu::COPY_BUFFER_ALIGNMENT).max(1)
            * wgpu::COPY_BUFFER_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let aligned = contents.len() / 4 * 4;
        self.queue.write_buffer(&buffer, 0, &contents[..aligned]);
        if aligned < contents.len() {
            let mut tail = [0u8; 4];
            tail[..contents.len() - aligned].copy_from_slice(&contents[aligned..]);
            self.queue.write_buffer(&buffer, aligned as u64, &tail);
        }
        Ok(buffer)
    }

    /// Blocks until the queue is idle, then reports any error raised meanwhile.
    pub fn wait(&self) -> Result<(), GpuError> {
        if let Err(e) = self.device.poll(wgpu::PollType::wait_indefinitely()) {
            self.check()?; // a lost device says so
            return Err(GpuError::Wgpu(e.to_string()));
        }
        self.check()
    }

    /// One line: adapter name, type, backend, driver.
    pub fn describe(&self) -> String {
        let i = &self.info;
        format!("{} ({:?}, {:?}, driver {} {})", i.name, i.device_type, i.backend, i.driver, i.driver_info)
    }

    /// The largest storage buffer binding this device accepts, in bytes.
    pub fn max_storage_binding(&self) -> u64 {
        self.device.limits().max_storage_buffer_binding_size
    }

    /// The largest buffer this device both creates and binds as storage, in bytes: what one
    /// uploaded buffer (a film, the scene's, the BVH's) may hold.
    pub fn upload_limit(&self) -> u64 {
        self.max_storage_binding().min(self.device.limits().max_buffer_size)
    }
}

#[cfg(test)]
mod tests {
    use super::pci_address;

    #[test]
    fn pci_addresses_parse_in_every_spelling() {
        let want = Some((0, 0x18, 0, 0));
        assert_eq!(pci_address("0000:18:00.0"), want);
        assert_eq!(pci_address("00000000:18:00.0"), want, "nvidia-smi's spelling");
        assert_eq!(pci_address("18:00.0"), want);
        assert_eq!(pci_address(" 0001:c1:1f.7 "), Some((1, 0xc1, 0x1f, 7)));
        for bad in ["", "0", "18:00", "GPU-1", "0000:18:00:00.0", "zz:00.0", "1:2:3.x"] {
            assert_eq!(pci_address(bad), None, "{bad}");
        }
    }
}
