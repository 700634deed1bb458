"""Writes DispersionPrisms.gltf (+ .bin, stripes.png): furnace's own test of
KHR_materials_dispersion, laid out like the Khronos DispersionTest (whose mesh file the snapshot
here lacks): clear glass prisms (apex up, axis along x) in rows of index (1.33, 1.5, 1.76, 2.42) and columns of
dispersion (0, 0.5, 1, 2, 5; Abbe number 20/dispersion), in front of a white backdrop with black
horizontal lines, under a white sky. Each prism (apex angle 40 degrees, apex up, axis
along x) bends the lines behind it down; with dispersion each wavelength by its own angle, so a
line's edges show spectra. Each row's apex angle gives its index the same minimum deviation
(20 degrees; a 40 degree prism of index 1.76 or 2.42 would reflect everything inside). Usage: python3 make.py (writes beside itself). CC0."""
import base64, json, math, struct, zlib
from pathlib import Path

here = Path(__file__).parent
IORS = [1.33, 1.5, 1.76, 2.42]
DISPERSIONS = [0.0, 0.5, 1.0, 2.0, 5.0]
DEVIATION = math.radians(20.0)
HEIGHT, LENGTH = 0.7, 0.8          # the prism's cross-section height (y) and length (x), m
BACK_Z, BACK_W, BACK_H = -6.0, 14.0, 12.0

pos, nrm, uv, idx = [], [], [], []


def face(points, normal, uvs=None):
    """A planar polygon (counter-clockwise seen from `normal`) as a fan, flat-shaded."""
    base = len(pos) // 3
    for k, p in enumerate(points):
        pos.extend(p)
        nrm.extend(normal)
        uv.extend(uvs[k] if uvs else (0.0, 0.0))
    for k in range(1, len(points) - 1):
        idx.extend([base, base + k, base + k + 1])


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def unit(a):
    n = math.sqrt(sum(c * c for c in a))
    return [c / n for c in a]


def polygon(points):
    face(points, unit(cross(sub(points[1], points[0]), sub(points[2], points[0]))))


def apex_for(n):
    """The apex angle whose minimum deviation is DEVIATION: n sin(A/2) = sin((A + D)/2)."""
    lo, hi = 1e-3, math.pi / 2
    for _ in range(60):
        mid = (lo + hi) / 2
        if 2 * math.asin(min(1.0, n * math.sin(mid / 2))) - mid < DEVIATION:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def prism(apex_angle):
    """A prism about the origin: apex at +y, base at -y, faces towards +z and -z."""
    half_base = HEIGHT * math.tan(apex_angle / 2)
    apex, front, back = (HEIGHT / 2, 0.0), (-HEIGHT / 2, half_base), (-HEIGHT / 2, -half_base)  # (y, z)
    x0, x1 = -LENGTH / 2, LENGTH / 2
    P = lambda x, yz: [x, yz[0], yz[1]]
    polygon([P(x0, apex), P(x0, front), P(x1, front), P(x1, apex)])   # front face (towards the camera)
    polygon([P(x0, back), P(x0, apex), P(x1, apex), P(x1, back)])     # back face
    polygon([P(x0, front), P(x0, back), P(x1, back), P(x1, front)])   # base
    polygon([P(x0, apex), P(x0, back), P(x0, front)])                 # ends
    polygon([P(x1, apex), P(x1, front), P(x1, back)])


# One prism per row, its vertices and indices in ranges of `pos` and `idx`.
ranges = []
for ior in IORS:
    v0, i0 = len(pos) // 3, len(idx)
    prism(apex_for(ior))
    ranges.append((v0, len(pos) // 3, i0, len(idx)))
prism_vertices, prism_indices = len(pos) // 3, len(idx)
# The backdrop, facing +z, its texture's v running down.
w, h = BACK_W / 2, BACK_H / 2
face([[-w, -h, BACK_Z], [w, -h, BACK_Z], [w, h, BACK_Z], [-w, h, BACK_Z]], [0, 0, 1],
     [(0, 1), (1, 1), (1, 0), (0, 0)])

blob = bytearray()


def view(data, fmt, count, kind, target, extra=None):
    global blob
    while len(blob) % 4:
        blob.append(0)
    start = len(blob)
    blob += struct.pack(f"<{len(data)}{fmt}", *data)
    views.append({"buffer": 0, "byteOffset": start, "byteLength": len(blob) - start, "target": target})
    a = {"bufferView": len(views) - 1, "componentType": 5126 if fmt == "f" else 5125, "count": count, "type": kind}
    a.update(extra or {})
    accessors.append(a)
    return len(accessors) - 1


views, accessors = [], []
n = len(pos) // 3
rows = []
for v0, v1, i0, i1 in ranges:
    ps = pos[3 * v0: 3 * v1]
    bounds = {"min": [min(ps[i::3]) for i in range(3)], "max": [max(ps[i::3]) for i in range(3)]}
    rows.append((view(ps, "f", v1 - v0, "VEC3", 34962, bounds), view(nrm[3 * v0: 3 * v1], "f", v1 - v0, "VEC3", 34962),
                 view([k - v0 for k in idx[i0:i1]], "I", i1 - i0, "SCALAR", 34963)))
bp = pos[3 * prism_vertices:]
p_back = view(bp, "f", 4, "VEC3", 34962, {"min": [min(bp[i::3]) for i in range(3)], "max": [max(bp[i::3]) for i in range(3)]})
n_back = view(nrm[3 * prism_vertices:], "f", 4, "VEC3", 34962)
t_back = view(uv[2 * prism_vertices:], "f", 4, "VEC2", 34962)
i_back = view([i - prism_vertices for i in idx[prism_indices:]], "I", 6, "SCALAR", 34963)
(here / "DispersionPrisms.bin").write_bytes(bytes(blob))


def png(width, height, texel):
    raw = b"".join(b"\0" + bytes(v for x in range(width) for v in texel(x, y)) for y in range(height))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


# 32 black lines of 3/8 of their period down the backdrop's height (a period of 0.375 m).
(here / "stripes.png").write_bytes(png(4, 256, lambda x, y: (0, 0, 0) if y % 8 < 3 else (255, 255, 255)))

materials = [{"name": "backdrop", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0,
                                                           "roughnessFactor": 1}}]
meshes = [{"name": "backdrop", "primitives": [{"attributes": {"POSITION": p_back, "NORMAL": n_back, "TEXCOORD_0": t_back},
                                               "indices": i_back, "material": 0}]}]
nodes = [{"name": "backdrop", "mesh": 0}]
for r, ior in enumerate(IORS):
    for c, d in enumerate(DISPERSIONS):
        ext = {"KHR_materials_transmission": {"transmissionFactor": 1.0},
               "KHR_materials_volume": {"thicknessFactor": HEIGHT}, "KHR_materials_ior": {"ior": ior}}
        if d > 0:
            ext["KHR_materials_dispersion"] = {"dispersion": d}
        materials.append({"name": f"ior{ior}_d{d}", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1],
                          "metallicFactor": 0, "roughnessFactor": 0}, "extensions": ext})
        meshes.append({"name": f"prism_ior{ior}_d{d}", "primitives": [
            {"attributes": {"POSITION": rows[r][0], "NORMAL": rows[r][1]}, "indices": rows[r][2],
             "material": len(materials) - 1}]})
        nodes.append({"name": f"prism_ior{ior}_d{d}", "mesh": len(meshes) - 1,
                      "translation": [(c - 2) * 1.1, (1.5 - r) * 1.15, 0.0]})
nodes.append({"name": "camera", "camera": 0, "translation": [0.0, 0.0, 11.0]})
gltf = {
    "asset": {"version": "2.0", "generator": "furnace tests/data/scenes/DispersionPrisms/make.py",
              "copyright": "CC0 1.0: furnace's own test scene"},
    "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior",
                       "KHR_materials_dispersion"],
    "scene": 0,
    "scenes": [{"nodes": list(range(len(nodes))), "extras": {"background_radiance_rgb": [0.8, 0.8, 0.8]}}],
    "nodes": nodes, "meshes": meshes, "materials": materials,
    "textures": [{"source": 0, "sampler": 0}], "images": [{"uri": "stripes.png"}],
    "samplers": [{"magFilter": 9728, "minFilter": 9728}],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.46, "aspectRatio": 1.25, "znear": 0.1}}],
    "accessors": accessors, "bufferViews": views,
    "buffers": [{"uri": "DispersionPrisms.bin", "byteLength": len(blob)}],
}
(here / "DispersionPrisms.gltf").write_text(json.dumps(gltf, indent=1) + "\n")
