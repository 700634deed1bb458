#!/usr/bin/env python3
"""Environment maps for the environment-map measurements (docs/accuracy.md, BENCHMARKS.md).

    make_env_maps.py tiny-sun OUT.exr [W H]   sky + a 0.1 deg sun (E = 5 W/m^2): one very bright texel
    make_env_maps.py sky OUT.exr W H          the same sky with a 0.5 deg sun (the 8192x4096 test)

Lat-long, row 0 at the top, texel-centred as tests/data/references/README.md rules. Each texel
holds the sky model at its centre plus the sun's radiance times the fraction of its cell inside
the disc (64 x 64 points per cell near the sun), as the reference maps are made. Written as float32
RGB OpenEXR through Mitsuba's Bitmap when Mitsuba is importable (the GPU machine), else through
the OpenEXR module; a `.hdr` path is written as Radiance RGBE by numpy alone. Needs numpy.
"""
import math
import sys

import numpy as np

SUN = np.array([0.5, 0.6, 0.6]) / np.linalg.norm([0.5, 0.6, 0.6])  # towards the sun (camera side)
E_SUN = 5.0  # irradiance facing the sun, W/m^2


def directions(u, v):
    phi, theta = np.broadcast_arrays(2 * math.pi * u, math.pi * v)
    return np.stack([np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)], -1)


def sky_model(d):
    y = d[..., 1:2]
    zenith, horizon, ground = np.array([0.25, 0.4, 0.9]), np.array([1.0, 1.0, 1.05]), np.array([0.25, 0.22, 0.2])
    t = np.clip(y, 0, 1) ** 0.5
    above = horizon * (1 - t) + zenith * t
    blend = np.clip((y + 0.02) / 0.04, 0, 1)
    return ground * (1 - blend) + above * blend


def make(w, h, diameter_deg):
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    img = sky_model(directions(u[None, :], v[:, None])).astype(np.float64)
    half = math.radians(diameter_deg) / 2
    cos_half = math.cos(half)
    radiance = E_SUN / (math.pi * math.sin(half) ** 2)
    # The cells near the sun: its (u, v) and a margin of a few cells.
    su = (math.atan2(SUN[0], -SUN[2]) / (2 * math.pi)) % 1.0
    sv = math.acos(SUN[1]) / math.pi
    r = int(math.ceil(half / math.pi * h)) + 2
    ci, cj = int(su * w), int(sv * h)
    n = 64
    sub = (np.arange(n) + 0.5) / n
    for j in range(max(cj - r, 0), min(cj + r + 1, h)):
        rr = int(math.ceil(r / max(math.sin(math.pi * (j + 0.5) / h), 1e-3)))
        for i in range(ci - rr, ci + rr + 1):
            uu = ((i % w) + sub[None, :]) / w
            vv = (j + sub[:, None]) / h
            inside = (directions(uu, vv) @ SUN) >= cos_half
            frac = inside.mean()
            if frac > 0:
                img[j, i % w] += radiance * frac
    return img.astype(np.float32)


def write_hdr(path, img):
    """Radiance RGBE, flat scanlines (8 bits of mantissa, a shared exponent: 10^6 fits)."""
    h, w, _ = img.shape
    m = img.max(-1).astype(np.float64)
    f, e = np.frexp(m)
    scale = np.where(m > 1e-32, f * 256.0 / np.maximum(m, 1e-32), 0.0)
    rgbe = np.zeros((h, w, 4), np.uint8)
    rgbe[..., :3] = np.clip(img * scale[..., None], 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(m > 1e-32, e + 128, 0).astype(np.uint8)
    with open(path, "wb") as fh:
        fh.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w))
        fh.write(rgbe.tobytes())


def write(path, img):
    if path.endswith(".hdr"):
        return write_hdr(path, img)
    try:
        import mitsuba as mi
    except ImportError:
        mi = None
    if mi is not None:
        # mi.variants() lists every variant built, also those pruned from a packed install.
        for variant in ("cuda_ad_rgb", "llvm_ad_rgb", "scalar_rgb"):
            try:
                mi.set_variant(variant)
                break
            except Exception:
                continue
        mi.Bitmap(img).write(path)
    else:
        import OpenEXR
        OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                     {"RGB": img}).write(path)


if __name__ == "__main__":
    kind, out = sys.argv[1], sys.argv[2]
    if kind == "tiny-sun":
        w, h = (int(sys.argv[3]), int(sys.argv[4])) if len(sys.argv) > 4 else (2048, 1024)
        img = make(w, h, 0.1)
    elif kind == "sky":
        img = make(int(sys.argv[3]), int(sys.argv[4]), 0.5)
    else:
        sys.exit(__doc__)
    write(out, img)
    print(f"{out}: {img.shape[1]}x{img.shape[0]}, max {img.max():.4g}, mean {img.mean():.4g}")
