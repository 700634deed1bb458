//! Memory planned before a render: the host bytes its film, the CPU integrator's pass buffer,
//! the BVH and the written outputs will take, against what this process may still allocate (the
//! machine's available memory, its cgroup's limit, the address-space limit). A render that
//! cannot fit is refused before any work, naming the sizes and what to change, rather than
//! aborted by the allocator minutes in.

use furnace_cpu::CpuRenderer;
use furnace_render::{Film, RenderSettings};
use std::fmt::Write as _;

/// Host bytes per triangle of the BVH and its build (the triangle references, bounds and
/// Morton codes of the build on top of the finished nodes), over the scene's own arrays.
const BVH_BYTES_PER_TRIANGLE: u64 = 256;

/// Bytes per pixel that writing the EXR and PNG takes besides the film's copy and the EXR's
/// channels: the linear image as `f32` three times (the means, the PNG's input, the EXR's) and
/// the 8-bit PNG.
const OUTPUT_IMAGE_BYTES_PER_PIXEL: u64 = 3 * 12 + 3;

/// Host bytes per instance: its transforms (object to world, world to object, the normal
/// matrix), its mesh and mirror flag, and its share of the TLAS (`furnace info` states 320 for
/// the built-in forest).
const INSTANCE_BYTES: u64 = 320;

/// Memory left to plan with: what the render may still allocate is at most this share of what
/// is free (the rest: the allocator's fragmentation, the threads' stacks, libraries, the page
/// cache the written files need).
const USABLE_SHARE: f64 = 0.9;

/// The host memory a render will take, part by part.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Each part's name and bytes.
    pub parts: Vec<(&'static str, u64)>,
    /// The scene's stored triangles (a mesh placed by several instances counted once).
    pub triangles: usize,
}

impl Plan {
    /// The plan of a render with `settings` of a scene of `triangles` triangles; `cpu`: on the
    /// CPU integrator (which adds its pass buffer and builds its BVH on the host; a GPU keeps
    /// its film in its own memory, but the host reads it back to write it).
    pub fn new(settings: &RenderSettings, triangles: usize, instances: usize, cpu: bool) -> Self {
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        let film = pixels * Film::bytes_per_pixel(settings);
        let mut parts = vec![("film", film)];
        if cpu {
            parts.push(("pass buffer", CpuRenderer::pass_buffer_bytes(settings)));
        }
        parts.push(("BVH", triangles as u64 * BVH_BYTES_PER_TRIANGLE));
        parts.push(("instances", instances as u64 * INSTANCE_BYTES));
        // The film read back (a copy), the EXR's 32-bit channels, the images.
        let channels = 4 * furnace_post::state_channel_count(settings.aovs, settings.adaptive.is_some());
        parts.push((
            "writing the EXR and PNG",
            pixels * (Film::bytes_per_pixel(settings) + channels + OUTPUT_IMAGE_BYTES_PER_PIXEL),
        ));
        Self { parts, triangles }
    }

    /// All parts.
    pub fn total(&self) -> u64 {
        self.parts.iter().map(|(_, b)| b).sum()
    }

    /// `Err` naming the sizes and what to change when the plan does not fit in `free` bytes
    /// (`limit` says what limits them).
    pub fn check(&self, settings: &RenderSettings, free: u64, limit: &str) -> Result<(), String> {
        let usable = (free as f64 * USABLE_SHARE) as u64;
        if self.total() <= usable {
            return Ok(());
        }
        let mut parts = String::new();
        for (i, (name, bytes)) in self.parts.iter().filter(|(_, b)| *b > 0).enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            let _ = write!(parts, "{sep}{name} {}", gb(*bytes));
        }
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        let per_pixel = self.total() / pixels.max(1);
        let scene_bytes: u64 =
            self.parts.iter().filter(|(n, _)| matches!(*n, "BVH" | "instances")).map(|(_, b)| b).sum();
        let mut change = if scene_bytes * 2 > self.total() {
            // The scene, not the image, is what does not fit.
            format!(
                "the scene's {} stored triangles are the most of it: render it on a machine with more \
                 memory, or with fewer triangles (a mesh repeated as glTF instances is stored once)",
                self.triangles
            )
        } else {
            format!("lower --width/--height (about {per_pixel} bytes per pixel)")
        };
        if settings.aovs {
            change.push_str(", or render without --aovs/--denoise");
        }
        let under = if limit.is_empty() { String::new() } else { format!(" under {limit}") };
        Err(format!(
            "a {}×{} render needs about {} of memory ({parts}) but {} are free{under} ({} usable): \
             {change}",
            settings.width,
            settings.height,
            gb(self.total()),
            gb(free),
            gb(usable),
        ))
    }
}

/// `bytes` in GB (10⁹), two significant decimals.
fn gb(bytes: u64) -> String {
    format!("{:.2} GB", bytes as f64 / 1e9)
}

/// The bytes this process may still allocate and what limits them: the least of the machine's
/// available memory (`MemAvailable`), the room under its cgroup's memory limit (v2 or v1), and
/// the room under its address-space limit (`ulimit -v`). `None` where none can be read.
pub fn free_memory() -> Option<(u64, &'static str)> {
    let mut best: Option<(u64, &'static str)> = None;
    let mut take = |bytes: Option<u64>, what: &'static str| {
        if let Some(b) = bytes
            && best.is_none_or(|(x, _)| b < x)
        {
            best = Some((b, what));
        }
    };
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    take(meminfo.as_deref().and_then(|m| kib_field(m, "MemAvailable:")), "");
    let read = |p: &str| std::fs::read_to_string(p).ok().and_then(|s| s.trim().parse::<u64>().ok());
    let cgroup_v2 = read("/sys/fs/cgroup/memory.max").zip(read("/sys/fs/cgroup/memory.current"));
    take(cgroup_v2.map(|(max, used)| max.saturating_sub(used)), "the cgroup's memory limit");
    let cgroup_v1 = read("/sys/fs/cgroup/memory/memory.limit_in_bytes")
        .zip(read("/sys/fs/cgroup/memory/memory.usage_in_bytes"));
    take(cgroup_v1.map(|(max, used)| max.saturating_sub(used)), "the cgroup's memory limit");
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let limits = std::fs::read_to_string("/proc/self/limits").ok();
    let address_space = limits.as_deref().and_then(address_space_limit);
    let mapped = status.as_deref().and_then(|s| kib_field(s, "VmSize:"));
    take(
        address_space.zip(mapped).map(|(max, used)| max.saturating_sub(used)),
        "the address-space limit (ulimit -v)",
    );
    best
}

/// A `NAME: N kB` field of a `/proc` file, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

/// The soft "Max address space" of `/proc/self/limits`, in bytes (`None` when unlimited).
fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..].split_whitespace().next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_fields_parse() {
        assert_eq!(
            kib_field("MemTotal: 10 kB\nMemAvailable:    2048 kB\n", "MemAvailable:"),
            Some(2048 * 1024)
        );
        assert_eq!(kib_field("MemTotal: 10 kB\n", "MemAvailable:"), None);
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         8589934592           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(8_589_934_592));
        let unlimited = "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_space_limit(unlimited), None);
    }

    /// The plan of an 8192² CPU render is ~151 bytes per pixel, what a 2048² render measured
    /// (peak RSS 655 MB against 180 MB at 1024²: 151 bytes per added pixel); it is refused
    /// under 8 GB, naming the film and the way out, and fits under 16 GB.
    #[test]
    fn a_large_render_is_refused_with_its_sizes() {
        let settings = RenderSettings { width: 8192, height: 8192, ..Default::default() };
        let plan = Plan::new(&settings, 0, 0, true);
        let per_pixel = plan.total() as f64 / (8192.0 * 8192.0);
        assert!((140.0..=170.0).contains(&per_pixel), "{per_pixel} bytes per pixel");
        let err = plan.check(&settings, 8_000_000_000, "the cgroup's memory limit").unwrap_err();
        assert!(
            err.contains("8192×8192") && err.contains("film 2.15 GB") && err.contains("--width"),
            "{err}"
        );
        assert!(plan.check(&settings, 16_000_000_000, "").is_ok());
    }

    #[test]
    fn aovs_and_adaptive_sampling_cost_more_and_say_so() {
        let plain = RenderSettings { width: 1024, height: 1024, ..Default::default() };
        let aovs = RenderSettings { aovs: true, ..plain };
        let (p, a) = (Plan::new(&plain, 0, 0, true).total(), Plan::new(&aovs, 0, 0, true).total());
        assert!(a > 2 * p, "AOVs: {a} vs {p}");
        let err = Plan::new(&aovs, 0, 0, true).check(&aovs, 100_000_000, "").unwrap_err();
        assert!(err.contains("--aovs"), "{err}");
    }

    /// A scene of 10⁸ stored triangles and 10⁵ instances at 1080p: the BVH is the most of it
    /// (25.6 GB), so the message names the scene and what to change about it, not the image.
    #[test]
    fn a_scene_too_large_is_refused_naming_the_scene() {
        let settings = RenderSettings { width: 1920, height: 1080, ..Default::default() };
        let plan = Plan::new(&settings, 100_000_000, 100_000, true);
        let err = plan.check(&settings, 24_000_000_000, "").unwrap_err();
        assert!(err.contains("BVH 25.60 GB") && err.contains("instances 0.03 GB"), "{err}");
        assert!(err.contains("100000000 stored triangles") && !err.contains("--width"), "{err}");
        assert!(plan.check(&settings, 40_000_000_000, "").is_ok());
    }

    #[test]
    fn this_machine_reports_some_free_memory() {
        let (free, _) = free_memory().expect("Linux has /proc/meminfo");
        assert!(free > 0);
    }
}
