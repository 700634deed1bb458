//! Opens a window on the built-in Cornell box rendering on the best GPU adapter; saving (Ctrl+S)
//! prints what would be written. `cargo run --release -p furnace-view --example view_cbox`
//! (needs an X11 or Wayland display and a Vulkan, Metal or DX12 adapter).

use furnace_gpu::{AdapterChoice, GpuContext, GpuRenderer};
use furnace_render::RenderSettings;
use furnace_scene::{Scene, builtin};
use furnace_view::{SaveRequest, ViewConfig, ViewHost};

/// A host that only reports what a save would hold.
struct PrintSaves;

impl ViewHost for PrintSaves {
    fn save(&mut self, _scene: &Scene, r: SaveRequest) -> Result<String, String> {
        let m = r.film.mean(0);
        Ok(format!("{} spp in {:.1} s; pixel (0, 0) = {:.4} {:.4} {:.4}", r.spp, r.seconds, m.x, m.y, m.z))
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = builtin::cornell_box()?;
    let camera = scene.default_camera();
    let settings = RenderSettings { width: 512, height: 512, ..RenderSettings::default() };
    let gpu = GpuRenderer::new(GpuContext::new(&AdapterChoice::Best)?, &scene, &camera, settings)?;
    let config = ViewConfig {
        title: "furnace-view example".into(),
        settings,
        camera,
        fixed_size: false,
        target_spp: None,
        time_limit: None,
        exposure: 0.0,
        tonemap: furnace_post::Tonemap::Aces,
        resume: None,
        script: None,
    };
    furnace_view::run(gpu, scene, config, &mut PrintSaves)?;
    Ok(())
}
