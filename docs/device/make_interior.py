#!/usr/bin/env python3
"""Writes furnace's built-in sunlit interior (`interior:N`, furnace_scene::builtin::sunlit_interior)
as a glTF that both furnace and the Mitsuba oracle (../shared/oracle/render_ref.py) read: the same
room (12 x 4 x 10 m, 0.5 m quads, three windows in the +x wall), the same grid of UV spheres, the
same materials (Lambert = specular 0, the metal = GGX alpha 0.1 with F = 1, given to Mitsuba as
`roughconductor`), camera and delta sun (irradiance (1000, 950, 850), black sky).

    python3 make_interior.py OUT_DIR [N_TRIANGLES] [--width W --height H --bounces B] [--lamps]

writes OUT_DIR/interior_N.gltf + .bin (numpy only). With --lamps, OUT_DIR/lit_room_N.gltf: the
same room lit also from inside, where the light is complicated: twelve ceiling panels (each 1 x 0.5 m
in 4 x 2 quads, 192 emissive triangles, radiance 10 x (1, 0.97, 0.9)), a 10 m strip along the
back wall (40 quads, 80 emissive triangles, radiance 30 x (1, 0.5, 0.2)), and two point lamps
(15 x (1, 0.85, 0.6) W/sr), the sun ten times lower (irradiance 100 x (1, 0.95, 0.85)) so that
the room's own lights matter as much; every emitter one-sided, the references' convention. furnace renders it as
`furnace bench --scene OUT_DIR/interior_N.gltf --masking separable --compensation off --bounces B`,
Mitsuba with `render_ref.py interior_N cuda_ad_rgb SPP PASSES` (max_depth B + 1).
"""
import json
import math
import os
import struct
import sys

import numpy as np

ROOM = np.array([12.0, 4.0, 10.0])
WINDOWS = [((-4.0, -2.5), (1.0, 3.0)), ((-1.0, 1.0), (1.0, 3.0)), ((2.5, 4.0), (1.0, 3.0))]
CELL = 0.5


PANEL, STRIP = 7, 8   # the emitters' material indices (after the room's seven)


def interior(target, lamps=False):
    pos, nrm, tris, mats = [], [], [], []

    def quads(origin, u, v, nu, nv, normal, material):
        """An nu x nv grid of quads spanning origin + [0, 1] u + [0, 1] v, facing u x v."""
        origin, u, v = map(np.asarray, (origin, u, v))
        for j in range(nv):
            for i in range(nu):
                base = len(pos)
                for s, t in ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)):
                    pos.append(origin + s / nu * u + t / nv * v)
                    nrm.append(normal)
                tris.extend([(base, base + 1, base + 2), (base, base + 2, base + 3)])
                mats.extend([material, material])

    def wall(origin, u, v, normal, material, keep):
        origin, u, v = map(np.asarray, (origin, u, v))
        su, sv = np.linalg.norm(u), np.linalg.norm(v)
        nu, nv = max(1, int(round(su / CELL))), max(1, int(round(sv / CELL)))
        for j in range(nv):
            for i in range(nu):
                s0, s1, t0, t1 = i / nu, (i + 1) / nu, j / nv, (j + 1) / nv
                if not keep((s0 + s1) * 0.5 * su, (t0 + t1) * 0.5 * sv):
                    continue
                base = len(pos)
                for s, t in ((s0, t0), (s1, t0), (s1, t1), (s0, t1)):
                    pos.append(origin + s * u + t * v)
                    nrm.append(normal)
                # Wound so that the front face (u x v) is the side `normal` faces.
                if np.dot(np.cross(u, v), normal) > 0:
                    tris.extend([(base, base + 1, base + 2), (base, base + 2, base + 3)])
                else:
                    tris.extend([(base, base + 2, base + 1), (base, base + 3, base + 2)])
                mats.extend([material, material])

    hx, hz, y1 = ROOM[0] / 2, ROOM[2] / 2, ROOM[1]
    x0, x1, z0, z1 = -hx, hx, -hz, hz
    X, Y, Z = np.eye(3)
    def everywhere(s, t):
        return True
    wall((x0, 0, z0), X * ROOM[0], Z * ROOM[2], Y, 0, everywhere)
    wall((x0, y1, z0), X * ROOM[0], Z * ROOM[2], -Y, 0, everywhere)
    wall((x0, 0, z0), Z * ROOM[2], Y * y1, X, 0, everywhere)
    wall((x0, 0, z0), X * ROOM[0], Y * y1, Z, 1, everywhere)
    wall((x0, 0, z1), X * ROOM[0], Y * y1, -Z, 2, everywhere)
    def outside_windows(s, t):
        z = z0 + s
        return not any(za < z < zb and ya < t < yb for (za, zb), (ya, yb) in WINDOWS)
    wall((x1, 0, z0), Z * ROOM[2], Y * y1, -X, 0, outside_windows)

    if lamps:
        # Ceiling panels 1 cm below the ceiling, facing down (X x Z = -Y); a strip 2.5 m above
        # the floor on the back wall, facing into the room (X x Y = +Z), 1 cm off it.
        for a in range(4):
            for b in range(3):
                cx, cz = x0 + (a + 0.5) * ROOM[0] / 4, z0 + (b + 0.5) * ROOM[2] / 3
                quads((cx - 0.5, y1 - 0.01, cz - 0.25), X * 1.0, Z * 0.5, 4, 2, -Y, PANEL)
        quads((-5.0, 2.5, z0 + 0.01), X * 10.0, Y * 0.06, 40, 1, Z, STRIP)

    remaining = max(0, target - len(tris))
    if remaining > 0:
        k = min(100, max(1, math.ceil(math.sqrt(remaining / 2000.0))))
        per = remaining / (k * k)
        n = max(3, int(round((1 + math.sqrt(1 + per)) / 2)))
        pitch = np.array([(ROOM[0] - 2) / k, 0.0, (ROOM[2] - 2) / k])
        radius = 0.35 * min(pitch[0], pitch[2])
        rings, segs = n, 2 * n
        r_ = np.arange(rings + 1)[:, None]
        s_ = np.arange(segs + 1)[None, :]
        theta = math.pi * r_ / rings
        phi = 2 * math.pi * s_ / segs
        d = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta) * np.ones_like(phi),
                      -np.sin(theta) * np.sin(phi)], -1).reshape(-1, 3)
        local = []
        idx = lambda r, s: r * (segs + 1) + s
        for r in range(rings):
            for s in range(segs):
                a, b, c, dd = idx(r, s), idx(r + 1, s), idx(r + 1, s + 1), idx(r, s + 1)
                if r != 0:
                    local.append((a, b, dd))
                if r != rings - 1:
                    local.append((b, c, dd))
        local = np.array(local)
        for a in range(k):
            for b in range(k):
                centre = np.array([x0 + 1 + (a + 0.5) * pitch[0], radius, z0 + 1 + (b + 0.5) * pitch[2]])
                base = len(pos)
                pos.extend(centre + radius * d)
                nrm.extend(d)
                tris.extend(local + base)
                mats.extend([3 + (a + b) % 4] * len(local))
    return (np.array(pos, np.float32), np.array(nrm, np.float32), np.array(tris, np.uint32),
            np.array(mats), (x0, x1, z0, z1))


def quat_from_matrix(m):
    """A unit quaternion (x, y, z, w) of the rotation matrix m (columns = axes)."""
    t = m[0, 0] + m[1, 1] + m[2, 2]
    if t > 0:
        s = math.sqrt(t + 1) * 2
        return [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    i = int(np.argmax([m[0, 0], m[1, 1], m[2, 2]]))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(1 + m[i, i] - m[j, j] - m[k, k]) * 2
    q = [0.0] * 4
    q[i] = s / 4
    q[j] = (m[j, i] + m[i, j]) / s
    q[k] = (m[k, i] + m[i, k]) / s
    q[3] = (m[k, j] - m[j, k]) / s
    return q


def look_at(eye, target, up=(0, 1, 0)):
    f = np.asarray(target, float) - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    return quat_from_matrix(np.stack([r, u, -f], 1))


def main():
    args = sys.argv[1:]
    opts = {"--width": 1920, "--height": 1440, "--bounces": 6}
    rest = []
    lamps = "--lamps" in args
    args = [a for a in args if a != "--lamps"]
    while args:
        a = args.pop(0)
        if a in opts:
            opts[a] = int(args.pop(0))
        else:
            rest.append(a)
    out = rest[0]
    target = int(float(rest[1])) if len(rest) > 1 else 20000
    pos, nrm, tris, mats, (x0, x1, z0, z1) = interior(target, lamps)
    name = f"{'lit_room' if lamps else 'interior'}_{len(tris)}"
    os.makedirs(out, exist_ok=True)
    lambert = lambda c, n: {"name": n, "pbrMetallicRoughness": {"baseColorFactor": c + [1.0], "metallicFactor": 0.0,
                            "roughnessFactor": 1.0}, "doubleSided": True,
                            "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}},
                            "extras": {"mitsuba": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": c}}}}
    white, red, green = [0.75, 0.75, 0.75], [0.7, 0.15, 0.1], [0.15, 0.6, 0.15]
    materials = [lambert(white, "white"), lambert(red, "red"), lambert(green, "green"),
                 lambert(white, "white_sphere"), lambert(red, "red_sphere"), lambert(green, "green_sphere"),
                 {"name": "metal", "pbrMetallicRoughness": {"baseColorFactor": [1.0] * 4, "metallicFactor": 1.0,
                  "roughnessFactor": math.sqrt(0.1)}, "doubleSided": True,
                  "extras": {"mitsuba": {"type": "roughconductor", "distribution": "ggx",
                             "alpha": 0.1, "sample_visible": True, "specular_reflectance": [1.0, 1.0, 1.0]}}}]

    def emitter(name, colour, strength):
        m = lambert([0.0, 0.0, 0.0], name)
        m["emissiveFactor"] = colour
        m["extensions"]["KHR_materials_emissive_strength"] = {"emissiveStrength": strength}
        m["extras"]["emission"] = "one-sided: front face (the side the normal points to) only"
        return m

    if lamps:
        materials += [emitter("panel", [1.0, 0.97, 0.9], 10.0), emitter("strip", [1.0, 0.5, 0.2], 30.0)]
    blob = bytearray()
    accessors, views, meshes, nodes = [], [], [], []

    def add(arr, target_kind, comp, typ, minmax=False):
        off = len(blob)
        blob.extend(arr.tobytes())
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": off, "byteLength": arr.nbytes, "target": target_kind})
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": len(arr), "type": typ}
        if minmax:
            acc["min"] = arr.min(0).tolist()
            acc["max"] = arr.max(0).tolist()
        accessors.append(acc)
        return len(accessors) - 1

    for m in sorted(set(mats.tolist())):
        sel = tris[mats == m]
        used, inv = np.unique(sel, return_inverse=True)
        p = add(pos[used], 34962, 5126, "VEC3", True)
        n = add(nrm[used], 34962, 5126, "VEC3")
        i = add(inv.astype(np.uint32).reshape(-1), 34963, 5125, "SCALAR")
        meshes.append({"name": materials[m]["name"], "primitives": [{"attributes": {"POSITION": p, "NORMAL": n},
                       "indices": i, "material": m}]})
        nodes.append({"name": materials[m]["name"], "mesh": len(meshes) - 1})
    eye = np.array([x0 + 0.5, 1.6, z1 - 0.5])
    nodes.append({"name": "camera", "camera": 0, "translation": eye.tolist(),
                  "rotation": look_at(eye, [x1, 1.2, -1.0])})
    sun = np.array([-1.0, -0.7, 0.15])
    sun /= np.linalg.norm(sun)
    # A directional light shines along its node's -Z: a frame whose -Z is the direction of travel.
    nodes.append({"name": "sun", "rotation": look_at(np.zeros(3), sun, up=(0, 0, 1)),
                  "extensions": {"KHR_lights_punctual": {"light": 0}},
                  "extras": {"direction_of_travel": sun.tolist()}})
    # The lit room's sun is low (100 W/m²): the room's own lights then give as much light as it.
    sun_e = 100.0 if lamps else 1000.0
    lights = [{"name": "sun", "type": "directional", "color": [1.0, 0.95, 0.85], "intensity": sun_e}]
    if lamps:
        for k, p in enumerate(([-3.0, 2.2, 2.0], [3.0, 2.2, -2.0])):
            nodes.append({"name": f"lamp{k}", "translation": p, "extensions": {"KHR_lights_punctual": {"light": k + 1}}})
            lights.append({"name": f"lamp{k}", "type": "point", "color": [1.0, 0.85, 0.6], "intensity": 15.0})
    w, h, b = opts["--width"], opts["--height"], opts["--bounces"]
    gltf = {
        "asset": {"version": "2.0", "generator": "furnace docs/device/make_interior.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_specular"]
        + (["KHR_materials_emissive_strength"] if lamps else []),
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": name, "nodes": list(range(len(nodes))), "extras": {
            "background_radiance_rgb": [0.0, 0.0, 0.0],
            "render": {"integrator": "path", "mitsuba_max_depth": b + 1, "max_bounces_equivalent": b,
                       "hide_emitters": False, "pixel_filter": "box (1 pixel)", "width": w, "height": h},
            "units": "metres; radiometric RGB; sun irradiance = color*intensity"}}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"name": "camera", "type": "perspective",
                     "perspective": {"yfov": 1.0, "aspectRatio": w / h, "znear": 0.01, "zfar": 1000.0}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": f"{name}.bin", "byteLength": len(blob)}],
    }
    open(os.path.join(out, f"{name}.bin"), "wb").write(blob)
    json.dump(gltf, open(os.path.join(out, f"{name}.gltf"), "w"), indent=1)
    print(os.path.join(out, f"{name}.gltf"), len(tris), "triangles")


if __name__ == "__main__":
    main()
