"""Renders a reference glTF scene with Blender Cycles on the CPU (the PyPI `bpy` 5.0 module).

    python cycles_render.py SCENE.gltf OUT.exr WIDTH HEIGHT SPP BOUNCES

Prints one JSON object: render_s (the timed render only), Msamples_per_s, the Blender version
and the threads Cycles used. The scene is imported by Blender's own glTF importer
(`bpy.ops.import_scene.gltf`), then set to the conventions of `../shared/references/README.md`
where the importer reads them otherwise:

- lights: `COMPAT` lighting units (no 683 lm/W: sun strength = irradiance in W/m², a point
  light's power = 4π × intensity in W/sr), point and spot lights of radius 0 without soft
  falloff, the sun's angular diameter from `extras.angular_diameter_deg` (0 = a delta sun);
- sky: `scenes[0].extras.background_radiance_rgb` as the world colour, or the lat-long map of
  `extras.environment` (linear, texel-centred) turned so that u = 0 looks down glTF's −Z;
- emitters one-sided (no emission from back faces), GGX without multiple-scattering
  compensation (as the references' separable-Smith metal, closest Cycles has);
- absorption: Beer–Lambert σ_a = −ln(attenuationColor)/attenuationDistance (the importer's
  Volume Absorption node uses density·(1 − colour));
- film: box filter one pixel wide, no adaptive sampling, no denoiser, no clamping, no glossy
  blur, no light threshold; `max_bounces` = BOUNCES − 1 (Cycles counts the bounces after the
  first hit; the references count scattering events), every per-kind limit the same.

What stays Cycles' own: its samplers, light tree, Russian roulette, height-correlated masking
and Principled BSDF (not exactly the references' model), and thin-walled glass sheets (Cycles
refracts through a single face as into a solid).

The sampling's time is the difference between a render of SPP samples per pixel and one of 1,
each timed whole (scene sync, BVH, film) after an untimed first render that loads what the
others reuse: render_s = (t(SPP) − t(1)) · SPP / (SPP − 1). Cycles' persistent data would keep
the BVH between renders, but with it a second render in background mode does not sample again.
"""

import json
import math
import os
import sys
import time

import bpy


def import_scene(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path, export_import_convert_lighting_mode="COMPAT")
    with open(path) as f:
        return json.load(f)


def set_lights(gltf):
    lights = gltf.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    by_name = {light.get("name"): light for light in lights}
    for light in bpy.data.lights:
        source = by_name.get(light.name, {})
        if light.type == "SUN":
            diameter = source.get("extras", {}).get("angular_diameter_deg", 0.0)
            light.angle = math.radians(diameter)
        elif light.type in ("POINT", "SPOT"):
            light.shadow_soft_size = 0.0
            if hasattr(light, "use_soft_falloff"):
                light.use_soft_falloff = False


def set_world(gltf, scene_dir):
    extras = gltf["scenes"][0].get("extras", {})
    world = bpy.data.worlds.new("references")
    bpy.context.scene.world = world
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    background = nodes["Background"]
    environment = extras.get("environment")
    if environment:
        texture = nodes.new("ShaderNodeTexEnvironment")
        texture.image = bpy.data.images.load(os.path.join(scene_dir, environment["uri"]))
        texture.image.colorspace_settings.name = "Non-Color"
        texture.interpolation = "Linear"
        texture.projection = "EQUIRECTANGULAR"
        # Cycles' u is 0.5 − atan2(y, x)/2π in Blender's Z-up frame; the references' is
        # atan2(x, −z)/2π in glTF's Y-up frame (−Z at u = 0): a quarter turn about +Z apart.
        coordinates = nodes.new("ShaderNodeTexCoord")
        mapping = nodes.new("ShaderNodeMapping")
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.pi / 2)
        links.new(coordinates.outputs["Generated"], mapping.inputs["Vector"])
        links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
        links.new(texture.outputs["Color"], background.inputs["Color"])
        background.inputs["Strength"].default_value = environment.get("intensity", 1.0)
    else:
        rgb = extras.get("background_radiance_rgb", [0.0, 0.0, 0.0])
        background.inputs["Color"].default_value = (*rgb, 1.0)
        background.inputs["Strength"].default_value = 1.0


def set_materials(gltf):
    volumes = {}
    for m in gltf.get("materials", []):
        volume = m.get("extensions", {}).get("KHR_materials_volume")
        if volume and "attenuationDistance" in volume:
            colour = volume.get("attenuationColor", [1.0, 1.0, 1.0])
            volumes[m.get("name")] = [
                -math.log(max(c, 1e-30)) / volume["attenuationDistance"] for c in colour
            ]
    for material in bpy.data.materials:
        if not material.use_nodes:
            continue
        nodes, links = material.node_tree.nodes, material.node_tree.links
        for node in list(nodes):
            if node.type == "BSDF_PRINCIPLED":
                node.distribution = "GGX"
                strength = node.inputs["Emission Strength"]
                if strength.default_value > 0.0 or strength.is_linked:
                    one_sided(nodes, links, strength)
            elif node.type == "VOLUME_ABSORPTION" and material.name in volumes:
                sigma = volumes[material.name]
                top = max(sigma)
                node.inputs["Density"].default_value = top
                node.inputs["Color"].default_value = (*[1.0 - s / top for s in sigma], 1.0)


def one_sided(nodes, links, strength):
    """Emission strength × (1 − backfacing): the references' emitters light their front only."""
    geometry = nodes.new("ShaderNodeNewGeometry")
    front = nodes.new("ShaderNodeMath")
    front.operation = "SUBTRACT"
    front.inputs[0].default_value = 1.0
    links.new(geometry.outputs["Backfacing"], front.inputs[1])
    scaled = nodes.new("ShaderNodeMath")
    scaled.operation = "MULTIPLY"
    if strength.is_linked:
        links.new(strength.links[0].from_socket, scaled.inputs[0])
    else:
        scaled.inputs[0].default_value = strength.default_value
    links.new(front.outputs["Value"], scaled.inputs[1])
    links.new(scaled.outputs["Value"], strength)


def set_render(width, height, spp, bounces):
    scene = bpy.context.scene
    cameras = [o for o in scene.objects if o.type == "CAMERA"]
    scene.camera = cameras[0]
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.use_persistent_data = False
    r.film_transparent = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.color_mode = "RGB"
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = 0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.light_sampling_threshold = 0.0
    depth = max(bounces - 1, 0)
    c.max_bounces = depth
    c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = depth
    c.volume_bounces = depth
    c.transparent_max_bounces = max(depth, 8)


def main():
    path, out = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    width, height, spp, bounces = (int(v) for v in sys.argv[3:7])
    gltf = import_scene(path)
    set_lights(gltf)
    set_world(gltf, os.path.dirname(path))
    set_materials(gltf)
    set_render(width, height, spp, bounces)
    scene = bpy.context.scene
    times = []
    # An untimed first render loads what later renders reuse (images, the environment's
    # importance map), so that the two timed ones differ by their samples alone.
    for samples in (1, 1, spp):
        scene.cycles.samples = samples
        t0 = time.perf_counter()
        bpy.ops.render.render()
        times.append(time.perf_counter() - t0)
    bpy.data.images["Render Result"].save_render(out)
    seconds = (times[2] - times[1]) * spp / max(spp - 1, 1)
    print(json.dumps({
        "blender": bpy.app.version_string,
        "threads": scene.render.threads,
        "width": width, "height": height, "spp": spp, "bounces": bounces,
        "render_s": seconds,
        "whole_render_s": times[2],
        "Msamples_per_s": width * height * spp / seconds / 1e6,
    }))


if __name__ == "__main__":
    main()
