//! The OIDN calls (only with the `oidn` feature), through the `oidn` crate's safe API.

use crate::{DenoiseError, DeviceKind, Options, Quality};
use std::time::Instant;

/// The output of [`run`]: packed `float3` pixels and the report.
pub(crate) struct Output {
    pub pixels: Vec<f32>,
    pub device: String,
    pub device_seconds: f64,
    pub prefilter_seconds: f64,
    pub seconds: f64,
}

fn oidn_error(context: &str) -> impl FnOnce(oidn::Error) -> DenoiseError + '_ {
    move |e| DenoiseError::Oidn(format!("{context}: {e}"))
}

/// Creates the device for `kind`: for [`DeviceKind::Default`] the first that OIDN can create.
fn new_device(kind: DeviceKind) -> Result<(oidn::Device, DeviceKind), DenoiseError> {
    let create = |kind: DeviceKind| match kind {
        DeviceKind::Cpu => oidn::Device::cpu(),
        DeviceKind::Cuda => oidn::Device::cuda(),
        DeviceKind::Hip => oidn::Device::hip(),
        DeviceKind::Sycl => oidn::Device::sycl(),
        DeviceKind::Metal => oidn::Device::metal(),
        DeviceKind::Default => oidn::Device::new(),
    };
    if kind != DeviceKind::Default {
        let device = create(kind).map_err(oidn_error(&format!("creating the {} device", kind.name())))?;
        return Ok((device, kind));
    }
    let gpus: &[DeviceKind] = if cfg!(target_os = "macos") {
        &[DeviceKind::Metal]
    } else {
        &[DeviceKind::Cuda, DeviceKind::Hip, DeviceKind::Sycl]
    };
    // A GPU kind without its module, driver or device fails in well under a millisecond.
    for &gpu in gpus {
        if let Ok(device) = create(gpu) {
            return Ok((device, gpu));
        }
    }
    let device = create(DeviceKind::Cpu)
        .map_err(oidn_error("creating the CPU device (after no GPU device could be created)"))?;
    Ok((device, DeviceKind::Cpu))
}

fn quality(q: Quality) -> oidn::Quality {
    match q {
        Quality::Default => oidn::Quality::Default,
        Quality::Fast => oidn::Quality::Fast,
        Quality::Balanced => oidn::Quality::Balanced,
        Quality::High => oidn::Quality::High,
    }
}

/// Denoises an LDR image in [0, 1] (a guide) in place with OIDN's LDR colour weights: the
/// approximation of OIDN's albedo/normal prefilters that the safe API allows (see
/// `Options::prefilter_guides`).
fn prefilter(
    device: &oidn::Device,
    w: usize,
    h: usize,
    image: &mut [f32],
    options: &Options,
    what: &str,
) -> Result<(), DenoiseError> {
    let mut filter = oidn::RayTracing::try_new(device).map_err(oidn_error("creating a filter"))?;
    filter.image_dimensions(w, h).hdr(false).srgb(false).filter_quality(quality(options.quality));
    filter.filter_in_place(image).map_err(oidn_error(&format!("prefiltering the {what} guide")))
}

pub(crate) fn run(
    w: usize,
    h: usize,
    color: &[f32],
    albedo: Option<&[f32]>,
    normal: Option<&[f32]>,
    options: &Options,
) -> Result<Output, DenoiseError> {
    let start = Instant::now();
    let (device, kind) = new_device(options.device)?;
    let device_seconds = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let mut albedo = albedo.map(<[f32]>::to_vec);
    let mut normal = normal.map(<[f32]>::to_vec);
    let mut prefilter_seconds = 0.0;
    if options.prefilter_guides && albedo.is_some() {
        let start = Instant::now();
        if let Some(albedo) = albedo.as_mut() {
            prefilter(&device, w, h, albedo, options, "albedo")?;
        }
        if let Some(normal) = normal.as_mut() {
            // [-1, 1] → [0, 1] for the LDR filter, and back.
            normal.iter_mut().for_each(|x| *x = x.mul_add(0.5, 0.5));
            prefilter(&device, w, h, normal, options, "normal")?;
            normal.iter_mut().for_each(|x| *x = x.mul_add(2.0, -1.0));
        }
        prefilter_seconds = start.elapsed().as_secs_f64();
    }

    let mut filter = oidn::RayTracing::try_new(&device).map_err(oidn_error("creating the filter"))?;
    filter.image_dimensions(w, h).hdr(options.hdr).srgb(false).filter_quality(quality(options.quality));
    // The buffer setters return errors; `albedo_normal(&[f32], &[f32])` would panic instead.
    match (albedo, normal) {
        (Some(albedo), Some(normal)) => {
            let albedo = device.create_buffer(&albedo).map_err(oidn_error("allocating the albedo"))?;
            let normal = device.create_buffer(&normal).map_err(oidn_error("allocating the normal"))?;
            filter.albedo_normal_buffer(albedo, normal).map_err(oidn_error("setting the guides"))?;
        }
        (Some(albedo), None) => {
            let albedo = device.create_buffer(&albedo).map_err(oidn_error("allocating the albedo"))?;
            filter.albedo_buffer(albedo).map_err(oidn_error("setting the albedo guide"))?;
        }
        // `check` rejects a normal without albedo.
        (None, _) => {}
    }
    // `clean_aux(true)` would be right after prefiltering, but the oidn crate 2.5.1 sends it
    // as `clean_aux`, which OIDN ignores: not set, so that nothing here pretends otherwise.
    let mut pixels = vec![0.0; color.len()];
    filter.filter(color, &mut pixels).map_err(oidn_error("filtering"))?;
    let seconds = start.elapsed().as_secs_f64();
    Ok(Output { pixels, device: format!("OIDN {}", kind.name()), device_seconds, prefilter_seconds, seconds })
}
