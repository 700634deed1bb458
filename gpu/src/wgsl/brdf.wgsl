// furnace-gpu: brdf module (see src/wgsl.rs).
