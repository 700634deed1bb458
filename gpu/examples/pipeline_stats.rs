//! What the Vulkan driver made of the integrator's megakernel: registers, local (spill) and
//! shared memory, instruction counts — the driver's `VK_KHR_pipeline_executable_properties`
//! statistics for the shader a scene would use, compiled with the runtime checks wgpu would add
//! or without them.
//!
//! ```sh
//! cargo run --release -p furnace-gpu --features pipeline-stats --example pipeline_stats -- \
//!     [SCENE.gltf|cbox|interior:N] [--checks checked|noloop|unchecked] [--aovs] [--f32-film] \
//!     [--counters] [--group-size N] [--stack N] [--spirv OUT.spv]
//! ```
//!
//! The SPIR-V is naga's, written with the options wgpu 30's Vulkan backend uses on a device with
//! `robustBufferAccess2` (buffer accesses left to the driver) and the runtime checks of
//! [`ShaderChecks`] (default: what every adapter gets, `noloop`; `checked` also bounds loops by a
//! counter). `--counters` compiles the counting kernel (`GpuRenderer::set_count_rays`) instead of
//! the rendering one. The workgroup size is what a hardware adapter with NVIDIA's limits gets
//! ([`furnace_gpu::integrator::default_group_size`]) unless `--group-size` gives one (a
//! multiple of 32 up to 1024), and the traversal stack what the scene's tree gets
//! ([`furnace_gpu::traverse::stack_size_for`]) unless `--stack` gives its node groups. The pipeline is created on the first
//! Vulkan device that has the extension (NVIDIA's driver has it; Mesa 22's software Vulkan does not:
//! then on the first device, for its compile time only — which for it leaves the LLVM
//! compile to the first dispatch), with its bindings from
//! [`furnace_gpu::integrator::binding_table`]. Nothing is dispatched.
#![allow(unsafe_code)]

use std::error::Error;
use std::ffi::CStr;

use ash::vk;
use furnace_accel::{BuildOptions, Bvh};
use furnace_gpu::film::FilmPrecision;
use furnace_gpu::integrator::{
    SceneFeatures, ShaderChecks, binding_table, default_group_size, pipeline_source,
};
use furnace_render::RenderSettings;
use furnace_scene::Scene;

struct Options {
    scene: String,
    /// None: the default (`ShaderChecks::default`).
    checks: Option<ShaderChecks>,
    aovs: bool,
    /// The counting kernel.
    counters: bool,
    precision: FilmPrecision,
    /// Invocations per workgroup; None: the hardware default.
    group_size: Option<u32>,
    /// Node groups of the traversal stack; None: the scene's tree's.
    stack: Option<u32>,
    spirv: Option<String>,
}

/// The positive integer that follows `flag`, at most `max`.
fn number(flag: &str, value: Option<String>, max: u32) -> Result<u32, String> {
    value
        .as_deref()
        .and_then(|v| v.parse::<u32>().ok())
        .filter(|&n| n > 0 && n <= max)
        .ok_or_else(|| format!("{flag} takes an integer from 1 to {max}, not {value:?}"))
}

fn parse() -> Result<Options, String> {
    let mut o = Options {
        scene: "cbox".into(),
        checks: None,
        aovs: false,
        counters: false,
        precision: FilmPrecision::F64,
        group_size: None,
        stack: None,
        spirv: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--checks" => match args.next().as_deref() {
                Some("checked") => o.checks = Some(ShaderChecks::Checked),
                Some("noloop") => o.checks = Some(ShaderChecks::NoLoopBounding),
                Some("unchecked") => o.checks = Some(ShaderChecks::Unchecked),
                other => return Err(format!("--checks takes checked, noloop or unchecked, not {other:?}")),
            },
            "--aovs" => o.aovs = true,
            "--counters" => o.counters = true,
            "--f32-film" => o.precision = FilmPrecision::F32Pass,
            "--group-size" => match number("--group-size", args.next(), 1024)? {
                n if n % 32 == 0 => o.group_size = Some(n),
                n => return Err(format!("--group-size takes a multiple of 32, not {n}")),
            },
            "--stack" => o.stack = Some(number("--stack", args.next(), 64)?),
            "--spirv" => o.spirv = Some(args.next().ok_or("--spirv needs a path")?),
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s => o.scene = s.to_string(),
        }
    }
    Ok(o)
}

fn load(scene: &str) -> Result<Scene, Box<dyn Error>> {
    if scene == "cbox" {
        return Ok(furnace_scene::builtin::cornell_box()?);
    }
    if let Some(n) = scene.strip_prefix("interior:") {
        return Ok(furnace_scene::builtin::sunlit_interior(n.parse::<f64>()? as u32));
    }
    Ok(Scene::load(scene)?)
}

/// naga's SPIR-V of `wgsl` as wgpu 30's Vulkan backend writes it (Vulkan 1.3, a device with
/// robustBufferAccess2) with `checks`.
fn spirv(wgsl: &str, checks: ShaderChecks) -> Result<Vec<u32>, Box<dyn Error>> {
    use naga::back::spv;
    use naga::proc::BoundsCheckPolicy as P;
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| e.emit_to_string(wgsl))?;
    let info =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
            .validate(&module)?;
    let mut options = spv::Options { lang_version: (1, 6), ..Default::default() };
    options.flags.remove(spv::WriterFlags::DEBUG);
    let c = checks.runtime_checks();
    options.bounds_check_policies = naga::proc::BoundsCheckPolicies {
        index: if c.bounds_checks { P::Restrict } else { P::Unchecked },
        buffer: P::Unchecked,
        image_load: P::Unchecked,
        binding_array: P::Unchecked,
    };
    options.force_loop_bounding = c.force_loop_bounding;
    options.emit_int_div_checks = c.int_div_checks;
    let pipeline =
        spv::PipelineOptions { shader_stage: naga::ShaderStage::Compute, entry_point: "main".into() };
    Ok(spv::write_vec(&module, &info, &options, Some(&pipeline))?)
}

fn main() -> Result<(), Box<dyn Error>> {
    let o = parse()?;
    let scene = load(&o.scene)?;
    let settings = RenderSettings { aovs: o.aovs, ..Default::default() };
    let features = SceneFeatures { trace_counters: o.counters, ..SceneFeatures::of(&scene, &settings) };
    // The workgroup size furnace would choose on a hardware adapter with NVIDIA's limits (1024
    // invocations, 48 KiB of workgroup memory), unless --group-size says otherwise.
    let group = o.group_size.unwrap_or(default_group_size(true, 1024, 48 * 1024, features));
    // The traversal stack sized by the scene's tree, as GpuRenderer sizes it.
    let stack = o.stack.unwrap_or_else(|| {
        let g = &scene.geometry;
        let depth = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default()).depth();
        furnace_gpu::traverse::stack_size_for(depth)
    });
    let wgsl = pipeline_source(o.precision, features, group, stack);
    let checks = o.checks.unwrap_or_default();
    let words = spirv(&wgsl, checks)?;
    if let Some(path) = &o.spirv {
        std::fs::write(path, bytemuck::cast_slice::<u32, u8>(&words))?;
    }
    println!(
        "scene {}: {:?}\nchecks {:?}, film {:?}, WGSL {} lines, SPIR-V {} words",
        o.scene,
        features,
        checks,
        o.precision,
        wgsl.lines().count(),
        words.len()
    );
    // SAFETY: plain Vulkan calls on objects created here, destroyed before returning; every
    // create-info outlives its call.
    unsafe { stats(&words, o.precision, features) }
}

unsafe fn stats(
    words: &[u32],
    precision: FilmPrecision,
    features: SceneFeatures,
) -> Result<(), Box<dyn Error>> {
    let entry = unsafe { ash::Entry::load()? };
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
    let instance =
        unsafe { entry.create_instance(&vk::InstanceCreateInfo::default().application_info(&app), None)? };
    let ext = ash::khr::pipeline_executable_properties::NAME;
    // The first device with the extension, else the first device (its compile time only).
    let mut chosen: Option<(vk::PhysicalDevice, String, u32, bool)> = None;
    for pd in unsafe { instance.enumerate_physical_devices()? } {
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let name = props.device_name_as_c_str()?.to_string_lossy().into_owned();
        let exts = unsafe { instance.enumerate_device_extension_properties(pd)? };
        let has = exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ext));
        println!("device {name}: {}", if has { "has the extension" } else { "no pipeline statistics" });
        if chosen.as_ref().is_none_or(|c| has && !c.3) {
            chosen = Some((pd, name, props.driver_version, has));
        }
    }
    let (pd, name, driver, has_stats) = chosen.ok_or("no Vulkan device")?;
    let family = unsafe { instance.get_physical_device_queue_family_properties(pd) }
        .iter()
        .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
        .ok_or("no compute queue")? as u32;
    // Every feature the device has (f64, int64, atomics, …), as the shader may need any of them.
    let mut v11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut f2 =
        vk::PhysicalDeviceFeatures2::default().push_next(&mut v11).push_next(&mut v12).push_next(&mut v13);
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let core = f2.features;
    let mut v11 = vk::PhysicalDeviceVulkan11Features { p_next: std::ptr::null_mut(), ..v11 };
    let mut v12 = vk::PhysicalDeviceVulkan12Features { p_next: std::ptr::null_mut(), ..v12 };
    let mut v13 = vk::PhysicalDeviceVulkan13Features { p_next: std::ptr::null_mut(), ..v13 };
    let mut pep = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
        .pipeline_executable_info(has_stats);
    let priorities = [1.0];
    let queues =
        [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    let extensions = if has_stats { vec![ext.as_ptr()] } else { Vec::new() };
    let mut info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&extensions)
        .enabled_features(&core)
        .push_next(&mut v11)
        .push_next(&mut v12)
        .push_next(&mut v13);
    if has_stats {
        info = info.push_next(&mut pep);
    }
    let device = unsafe { instance.create_device(pd, &info, None)? };

    let bindings: Vec<vk::DescriptorSetLayoutBinding> = binding_table(precision, features)
        .layout_entries()
        .iter()
        .map(|e| {
            let ty = match e.ty {
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    ..
                } => vk::DescriptorType::UNIFORM_BUFFER_DYNAMIC,
                wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, .. } => {
                    vk::DescriptorType::UNIFORM_BUFFER
                }
                _ => vk::DescriptorType::STORAGE_BUFFER,
            };
            vk::DescriptorSetLayoutBinding::default()
                .binding(e.binding)
                .descriptor_type(ty)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
        })
        .collect();
    let set_layout = unsafe {
        device.create_descriptor_set_layout(
            &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
            None,
        )?
    };
    let set_layouts = [set_layout];
    let layout = unsafe {
        device.create_pipeline_layout(
            &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts),
            None,
        )?
    };
    let module =
        unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(words), None)? };
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module)
        .name(c"main");
    let create = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout).flags(if has_stats {
        vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
    } else {
        vk::PipelineCreateFlags::empty()
    })];
    let started = std::time::Instant::now();
    let pipeline = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &create, None) }
        .map_err(|(_, e)| e)?[0];
    println!("{name} (driver {driver:#x}): pipeline compiled in {:.2} s", started.elapsed().as_secs_f64());
    let pep = ash::khr::pipeline_executable_properties::Device::new(&instance, &device);
    let executables = if has_stats {
        unsafe { pep.get_pipeline_executable_properties(&vk::PipelineInfoKHR::default().pipeline(pipeline))? }
    } else {
        Vec::new()
    };
    for (k, exe) in executables.iter().enumerate() {
        let text = |c: Result<&CStr, _>| c.map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        println!(
            "executable {k}: {} — {} (subgroup {})",
            text(exe.name_as_c_str()),
            text(exe.description_as_c_str()),
            exe.subgroup_size
        );
        let info = vk::PipelineExecutableInfoKHR::default().pipeline(pipeline).executable_index(k as u32);
        for s in unsafe { pep.get_pipeline_executable_statistics(&info)? } {
            // SAFETY: the union member is the one `format` names.
            let value = unsafe {
                match s.format {
                    vk::PipelineExecutableStatisticFormatKHR::BOOL32 => format!("{}", s.value.b32 != 0),
                    vk::PipelineExecutableStatisticFormatKHR::INT64 => format!("{}", s.value.i64),
                    vk::PipelineExecutableStatisticFormatKHR::UINT64 => format!("{}", s.value.u64),
                    vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => format!("{}", s.value.f64),
                    _ => "?".into(),
                }
            };
            println!("  {:<32} {value:>12}   {}", text(s.name_as_c_str()), text(s.description_as_c_str()));
        }
    }
    unsafe {
        device.destroy_pipeline(pipeline, None);
        device.destroy_shader_module(module, None);
        device.destroy_pipeline_layout(layout, None);
        device.destroy_descriptor_set_layout(set_layout, None);
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
    Ok(())
}
