// furnace-gpu: sampling module (see src/wgsl.rs).
