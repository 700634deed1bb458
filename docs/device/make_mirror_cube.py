# A closed cube of white, nearly smooth metal (roughness 0.05), camera and a point light inside:
# with Russian roulette off nearly every path reaches the bounce limit. Usage: make_mirror_cube.py OUT.gltf
import base64, json, struct, sys
v = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
idx = [i for a, b, c, d in faces for i in (a, b, c, a, c, d)]
pos = b''.join(struct.pack('<3f', *p) for p in v)
ind = b''.join(struct.pack('<H', i) for i in idx)
buf = pos + ind
g = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
     "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 5}]}},
     "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
     "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 0.5]},
               {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.3, 0.5, -0.2]}],
     "cameras": [{"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.01}}],
     "materials": [{"doubleSided": True, "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1, "roughnessFactor": 0.05}}],
     "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
     "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)}, {"buffer": 0, "byteOffset": len(pos), "byteLength": len(ind)}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1]},
                   {"bufferView": 1, "componentType": 5123, "count": len(idx), "type": "SCALAR"}]}
json.dump(g, open(sys.argv[1], 'w'))
