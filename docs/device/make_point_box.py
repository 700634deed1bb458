"""Writes a point-light box of N lights: cbox_point.gltf's two, then N - 2 dim ones of varied
colour on a 5-wide grid 0.15 m under the ceiling (the .bin stays cbox_point.bin's).

    python3 make_point_box.py N IN.gltf OUT.gltf
"""
import json
import sys

n, src, out = int(sys.argv[1]), sys.argv[2], sys.argv[3]
g = json.load(open(src))
lights = g['extensions']['KHR_lights_punctual']['lights']
scene = g['scenes'][0]
for i in range(n - 2):
    x, z = -0.8 + 0.4 * (i % 5), -0.75 + 0.3 * (i // 5)
    lights.append({'name': f'dim{i}', 'type': 'point', 'intensity': 0.02 + 0.01 * (i % 7),
                   'color': [0.6 + 0.4 * ((i * 3) % 5) / 4, 0.7, 0.6 + 0.4 * ((i * 2) % 5) / 4]})
    g['nodes'].append({'name': f'dim{i}', 'translation': [x, 1.55, z],
                       'extensions': {'KHR_lights_punctual': {'light': len(lights) - 1}}})
    scene['nodes'].append(len(g['nodes']) - 1)
json.dump(g, open(out, 'w'))
