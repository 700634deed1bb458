#!/usr/bin/env python3
"""Writes a glTF without one material extension, for measuring what that extension costs.

usage: strip-extension.py IN.gltf EXTENSION OUT.gltf

Removes EXTENSION from every material and from extensionsUsed/Required, and rewrites relative
buffer and image URIs so OUT may live in another folder than IN.
"""
import json
import os
import sys

src, extension, dst = sys.argv[1:4]
doc = json.load(open(src))
for material in doc.get("materials", []):
    material.get("extensions", {}).pop(extension, None)
for key in ("extensionsUsed", "extensionsRequired"):
    if key in doc:
        doc[key] = [e for e in doc[key] if e != extension]
src_dir, dst_dir = os.path.dirname(os.path.abspath(src)), os.path.dirname(os.path.abspath(dst))
for item in doc.get("buffers", []) + doc.get("images", []):
    uri = item.get("uri")
    if uri and not uri.startswith("data:") and "://" not in uri:
        item["uri"] = os.path.relpath(os.path.join(src_dir, uri), dst_dir)
json.dump(doc, open(dst, "w"), indent=1)
