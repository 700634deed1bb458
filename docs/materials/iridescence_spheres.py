"""Rebuilds the Khronos IridescenceDielectricSpheres scene where its mesh file cannot be had:
the 343 materials and sphere placements of its .gltf (7 x 7 x 7: base IOR x film IOR x film
thickness), on a UV sphere of radius 1 made here, with a camera near the screenshot's view.
Usage: python3 iridescence_spheres.py SOURCE.gltf OUT_DIR  (writes OUT_DIR/spheres.gltf, .bin)."""
import json, math, struct, sys
from pathlib import Path

src, out = json.loads(Path(sys.argv[1]).read_text()), Path(sys.argv[2])
out.mkdir(parents=True, exist_ok=True)
nu, nv = 48, 24
pos, nrm, idx = [], [], []
for j in range(nv + 1):
    t = math.pi * j / nv
    for i in range(nu + 1):
        p = 2 * math.pi * i / nu
        v = (math.sin(t) * math.sin(p), math.cos(t), math.sin(t) * math.cos(p))
        pos += v
        nrm += v
for j in range(nv):
    for i in range(nu):
        a, b = j * (nu + 1) + i, (j + 1) * (nu + 1) + i
        idx += [a, b, a + 1, a + 1, b, b + 1]
blob = struct.pack(f"<{len(pos)}f", *pos) + struct.pack(f"<{len(nrm)}f", *nrm) + struct.pack(f"<{len(idx)}I", *idx)
(out / "spheres.bin").write_bytes(blob)
n = len(pos) // 3
views = [{"buffer": 0, "byteOffset": 0, "byteLength": 12 * n}, {"buffer": 0, "byteOffset": 12 * n, "byteLength": 12 * n},
         {"buffer": 0, "byteOffset": 24 * n, "byteLength": 4 * len(idx)}]
accessors = [{"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1]},
             {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"},
             {"bufferView": 2, "componentType": 5125, "count": len(idx), "type": "SCALAR"}]
spheres = [nd for nd in src["nodes"] if nd["name"].startswith("Sphere")]
for mat in src["materials"]:  # the label planes' materials (not used here) lose their textures
    mat.get("pbrMetallicRoughness", {}).pop("baseColorTexture", None)
meshes, nodes = [], []
for k, nd in enumerate(spheres):
    material = src["meshes"][nd["mesh"]]["primitives"][0]["material"]
    meshes.append({"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": material}]})
    nodes.append({"mesh": k, "translation": nd.get("translation", [0, 0, 0])})
# A camera at `eye` looking at the cube's centre, +Y up (the rotation of -Z onto the view).
eye = [22.0, 16.0, 38.0]
f = [-e for e in eye]
fl = math.sqrt(sum(c * c for c in f))
f = [c / fl for c in f]
r = [-f[2], 0.0, f[0]]
rl = math.sqrt(sum(c * c for c in r))
r = [c / rl for c in r]
u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
m = [[r[0], u[0], -f[0]], [r[1], u[1], -f[1]], [r[2], u[2], -f[2]]]
w = math.sqrt(max(0.0, 1 + m[0][0] + m[1][1] + m[2][2])) / 2
q = [(m[2][1] - m[1][2]) / (4 * w), (m[0][2] - m[2][0]) / (4 * w), (m[1][0] - m[0][1]) / (4 * w), w]
nodes.append({"camera": 0, "translation": eye, "rotation": q})
gltf = {"asset": {"version": "2.0", "generator": "furnace docs/materials/iridescence_spheres.py"},
        "extensionsUsed": src["extensionsUsed"], "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes, "meshes": meshes, "materials": src["materials"], "accessors": accessors, "bufferViews": views,
        "buffers": [{"uri": "spheres.bin", "byteLength": len(blob)}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.75, "znear": 0.1, "aspectRatio": 1.0}}]}
(out / "spheres.gltf").write_text(json.dumps(gltf))
