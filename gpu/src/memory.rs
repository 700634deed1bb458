//! The device's memory, as its driver states it, against what a render will upload: a scene
//! that cannot fit is refused before anything is allocated, naming the sizes, rather than
//! failing part-way through the upload with an out-of-memory error that names none.
//!
//! wgpu does not report a device's memory; on Vulkan it is read from the physical device
//! (`vkGetPhysicalDeviceMemoryProperties2`, with `VK_EXT_memory_budget` where the driver has
//! it). On other backends the size is unknown and no check is made.

use crate::{GpuContext, GpuError};
use std::fmt::Write as _;

/// A device's memory: its largest device-local heap and, where the driver reports a budget, how
/// much of that heap this process may still allocate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceMemory {
    /// Bytes of the largest device-local heap.
    pub heap: u64,
    /// Bytes this process may allocate from it now (`VK_EXT_memory_budget`'s budget less its
    /// usage: other processes' allocations taken out); `None` where the driver reports no budget.
    pub free: Option<u64>,
}

impl DeviceMemory {
    /// What a new render may allocate: the budget's room where there is one, else the heap.
    pub fn available(&self) -> u64 {
        self.free.unwrap_or(self.heap).min(self.heap)
    }
}

/// Reads the memory of the Vulkan physical device under `adapter`; `None` on another backend.
/// Unsafe code: wgpu's Vulkan objects, read through ash.
#[allow(unsafe_code)]
#[cfg(all(not(target_arch = "wasm32"), any(windows, all(unix, not(target_vendor = "apple")))))]
fn vulkan_memory(adapter: &wgpu::Adapter) -> Option<DeviceMemory> {
    use ash::vk;
    // SAFETY: the adapter's instance and physical device are only queried for properties;
    // nothing is created, destroyed or kept past the guard.
    let hal = unsafe { adapter.as_hal::<wgpu::hal::api::Vulkan>() }?;
    let shared = hal.shared_instance();
    let instance = shared.raw_instance();
    let device = hal.raw_physical_device();
    // Memory properties2 is core from Vulkan 1.1 (ash's function pointer would be missing on an
    // older instance); the budget needs the device extension besides.
    let version_1_1 = vk::make_api_version(0, 1, 1, 0);
    // SAFETY: `device` belongs to `instance`, both alive while `hal` is.
    let properties = unsafe { instance.get_physical_device_properties(device) };
    let has_budget = shared.instance_api_version() >= version_1_1
        && properties.api_version >= version_1_1
        // SAFETY: as above.
        && unsafe { instance.enumerate_device_extension_properties(device) }.is_ok_and(|exts| {
            exts.iter().any(|e| e.extension_name_as_c_str() == Ok(ash::ext::memory_budget::NAME))
        });
    let mut budget = vk::PhysicalDeviceMemoryBudgetPropertiesEXT::default();
    let memory = if has_budget {
        let mut properties2 = vk::PhysicalDeviceMemoryProperties2::default().push_next(&mut budget);
        // SAFETY: as above; `budget` outlives the call that fills it.
        unsafe { instance.get_physical_device_memory_properties2(device, &mut properties2) };
        properties2.memory_properties
    } else {
        // SAFETY: as above.
        unsafe { instance.get_physical_device_memory_properties(device) }
    };
    let heaps = memory.memory_heaps_as_slice();
    let (index, heap) = heaps
        .iter()
        .enumerate()
        .filter(|(_, h)| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
        .max_by_key(|(_, h)| h.size)?;
    let free = has_budget.then(|| budget.heap_budget[index].saturating_sub(budget.heap_usage[index]));
    Some(DeviceMemory { heap: heap.size, free: free.filter(|&f| f > 0) })
}

#[cfg(not(all(not(target_arch = "wasm32"), any(windows, all(unix, not(target_vendor = "apple"))))))]
fn vulkan_memory(_adapter: &wgpu::Adapter) -> Option<DeviceMemory> {
    None
}

impl GpuContext {
    /// The device's memory as its driver states it; `None` where the backend does not say
    /// (wgpu reports no memory size; Vulkan's is read from the physical device).
    pub fn memory(&self) -> Option<DeviceMemory> {
        vulkan_memory(&self.adapter)
    }
}

/// `bytes` in GiB, two decimals (as a driver's heap sizes are powers of two).
pub(crate) fn gib(bytes: u64) -> String {
    format!("{:.2} GiB", bytes as f64 / f64::from(1u32 << 30))
}

/// [`GpuError::OutOfDeviceMemory`] when the `parts` (each a name and its bytes) add up to more
/// than `memory` has room for on `adapter`; the parts over 1 % of the total are named, largest
/// first.
pub fn check_fits(parts: &[(&str, u64)], memory: DeviceMemory, adapter: &str) -> Result<(), GpuError> {
    let needed: u64 = parts.iter().map(|(_, b)| b).sum();
    let available = memory.available();
    if needed <= available {
        return Ok(());
    }
    let mut sorted: Vec<&(&str, u64)> = parts.iter().filter(|(_, b)| *b * 100 >= needed).collect();
    sorted.sort_by_key(|(_, b)| std::cmp::Reverse(*b));
    let mut named = String::new();
    for (i, (name, bytes)) in sorted.iter().enumerate() {
        let _ = write!(named, "{}{name} {}", if i == 0 { "" } else { ", " }, gib(*bytes));
    }
    let offers = match memory.free {
        Some(free) if free < memory.heap => {
            format!("{} free of its {} of device memory", gib(free), gib(memory.heap))
        }
        _ => format!("{} of device memory", gib(memory.heap)),
    };
    Err(GpuError::OutOfDeviceMemory { needed, available, detail: format!("{named}; {adapter} has {offers}") })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GIB: u64 = 1 << 30;

    #[test]
    fn a_render_over_the_room_is_refused_naming_its_parts_and_the_room() {
        let parts = [("BVH", 70 * GIB), ("scene", 20 * GIB), ("film", GIB / 1000)];
        let heap = DeviceMemory { heap: 80 * GIB, free: None };
        let err = check_fits(&parts, heap, "NVIDIA H100").unwrap_err().to_string();
        assert!(err.contains("90.00 GiB"), "{err}");
        assert!(err.contains("BVH 70.00 GiB, scene 20.00 GiB"), "largest first: {err}");
        assert!(!err.contains("film 0.00"), "a part under 1 % is not named: {err}");
        assert!(err.contains("NVIDIA H100 has 80.00 GiB of device memory"), "{err}");
        assert!(err.contains("render it on the CPU"), "says what to do: {err}");
        // Within the heap but over what other processes left: refused, saying both.
        let busy = DeviceMemory { heap: 140 * GIB, free: Some(60 * GIB) };
        let err = check_fits(&parts, busy, "H200").unwrap_err().to_string();
        assert!(err.contains("60.00 GiB free of its 140.00 GiB"), "{err}");
        // Exactly the room fits; no budget reported: the heap is the room.
        assert!(check_fits(&[("all", 80 * GIB)], heap, "x").is_ok());
        assert!(check_fits(&[("all", 80 * GIB + 1)], heap, "x").is_err());
        assert!(check_fits(&parts, DeviceMemory { heap: 140 * GIB, free: Some(100 * GIB) }, "x").is_ok());
    }
}
