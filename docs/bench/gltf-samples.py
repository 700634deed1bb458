#!/usr/bin/env python3
"""The glTF Sample Assets table of docs/gltf-samples.md: every model of a glTF-Sample-Assets
checkout, each of its variants (glTF, glTF-Binary, glTF-Draco, glTF-KTX-BasisU, ...) loaded by
`furnace info`, the plain one rendered beside its screenshot, and each compressed or repacked
variant rendered too and scored against the plain one (`furnace compare`: relative MSE).

    python3 docs/bench/gltf-samples.py MODELS_DIR OUT_DIR [FURNACE]

MODELS_DIR is the checkout's Models/ folder; OUT_DIR receives table.md, results.json and the
thumbnails (thumbs/NAME.jpg: render left, screenshot right; needs ImageMagick's `convert`).
FURNACE defaults to target/release/furnace. WIDTH (256), HEIGHT (192), SPP (32) set the renders.
"""
import json, os, re, subprocess, sys, time

models, out = sys.argv[1], sys.argv[2]
furnace = sys.argv[3] if len(sys.argv) > 3 else "target/release/furnace"
w, h, spp = os.environ.get("WIDTH", "256"), os.environ.get("HEIGHT", "192"), os.environ.get("SPP", "32")
os.makedirs(os.path.join(out, "thumbs"), exist_ok=True)
work = os.path.join(out, "work")
os.makedirs(work, exist_ok=True)


def scene_file(folder):
    files = sorted(f for f in os.listdir(folder) if f.endswith((".gltf", ".glb")))
    return os.path.join(folder, files[0]) if files else None


def run(args, timeout=600):
    t = time.time()
    try:
        p = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
        return p.returncode, p.stdout + p.stderr, time.time() - t
    except subprocess.TimeoutExpired:
        return 124, "timed out", time.time() - t


results = []
for name in sorted(os.listdir(models)):
    d = os.path.join(models, name)
    if not os.path.isdir(d):
        continue
    variants = sorted(v for v in os.listdir(d) if v.startswith("glTF") and os.path.isdir(os.path.join(d, v)))
    row = {"model": name, "variants": {}}
    plain = None
    for v in variants:
        f = scene_file(os.path.join(d, v))
        if f is None:
            continue
        rc, text, _ = run([furnace, "info", f])
        lines = text.splitlines()
        count = next((l.split()[1] for l in lines if l.startswith("warnings")), "?")
        # The distinct warning messages (the part after the glTF path, without numbers).
        kinds = sorted({l.split(": ", 2)[-1][:90] for l in lines if l.startswith("  warning: ")})
        error = None if rc == 0 else text.strip().splitlines()[-1][:300]
        entry = {"file": os.path.relpath(f, models), "loads": rc == 0, "warnings": count, "kinds": kinds, "error": error}
        if rc == 0:
            stem = os.path.join(work, f"{name}-{v}")
            rc2, text2, secs = run([furnace, "render", f, "--spp", spp, "--width", w, "--height", h, "--out", stem])
            entry["rendered"] = rc2 == 0
            entry["render_s"] = round(secs, 2)
            entry["notes"] = [l for l in text2.splitlines() if l.startswith("note:")]
            if rc2 == 0 and plain is None and v in ("glTF", "glTF-Binary", "glTF-Embedded"):
                plain = stem
                entry["reference"] = True
            elif rc2 == 0 and plain is not None:
                rc3, text3, _ = run([furnace, "compare", stem + ".exr", plain + ".exr"])
                for l in text3.splitlines():
                    if l.startswith("relative MSE"):
                        entry["rel_mse_vs_plain"] = float(l.split()[2])
        row["variants"][v] = entry
    shots = os.path.join(d, "screenshot")
    shot = None
    if os.path.isdir(shots):
        for s in ("screenshot.png", "screenshot.jpg", "screenshot-x150.png", "screenshot-x150.jpg"):
            if os.path.exists(os.path.join(shots, s)):
                shot = os.path.join(shots, s)
                break
    if plain:
        # ASCII file names (a model is called Unicode❤♻Test).
        thumb = os.path.join(out, "thumbs", re.sub(r"[^A-Za-z0-9_-]", "_", name) + ".jpg")
        args = ["convert", plain + ".png", "-resize", f"{w}x{h}"]
        if shot:
            args += ["(", shot, "-resize", f"{w}x{h}", ")", "+append"]
        subprocess.run(args + ["-quality", "80", thumb])
        row["thumb"] = os.path.relpath(thumb, out)
    results.append(row)
    print(name, {v: (e["loads"], e["warnings"], e.get("rel_mse_vs_plain")) for v, e in row["variants"].items()}, flush=True)

json.dump(results, open(os.path.join(out, "results.json"), "w"), indent=1)

# The Markdown table: one row per model; per variant ✓ (warnings) and, for a repacked or
# compressed variant, its relative MSE against the plain file's render; the thumbnail.
lines = ["| model | variants: loads (warnings) [rel. MSE vs plain] | warnings (distinct) | render · screenshot |",
         "|---|---|---|---|"]
for row in results:
    cells, kinds = [], set()
    for v, e in row["variants"].items():
        if not e["loads"]:
            cells.append(f"{v} ✗ {e['error'].split(': ')[-1][:80]}")
            continue
        mse = e.get("rel_mse_vs_plain")
        cells.append(f"{v} ✓ ({e['warnings']})" + ("" if mse is None else f" [{mse:.1e}]"))
        kinds.update(e.get("kinds", []))
    thumb = f"![{row['model']}](gltf-samples/{os.path.basename(row['thumb'])})" if "thumb" in row else ""
    lines.append(f"| {row['model']} | {'<br>'.join(cells)} | {'<br>'.join(sorted(kinds))} | {thumb} |")
open(os.path.join(out, "table.md"), "w").write("\n".join(lines) + "\n")
