// furnace-gpu: traverse module (see src/wgsl.rs).
