#!/usr/bin/env bash
# Installs Intel Open Image Denoise 2.5.1 (shared libraries and trained weights) for furnace's
# `oidn` / `denoise` cargo features, and prints the directory to use as OIDN_DIR.
#
#   OIDN_DIR=$(bash denoise/install-oidn.sh)        # default prefix
#   bash denoise/install-oidn.sh /opt/oidn-2.5.1     # or: OIDN_PREFIX=/opt/oidn-2.5.1 bash …
#
# Debian has no OIDN package, and Intel's release tarball is a GitHub download; the PyPI wheel
# `pyoidn==2.5.1` carries the same official build (pyoidn/oidn/{lib,bin}: libOpenImageDenoise,
# its core, the CPU/CUDA/HIP/SYCL device modules, TBB, oidnDenoise), so pip fetches it — from
# PyPI or whatever index pip is configured for — and this script unpacks that part:
#
#   $PREFIX/lib/libOpenImageDenoise.so -> .so.2 -> .so.2.5.1 (+ core, device modules, libtbb…)
#   $PREFIX/bin/oidnDenoise, oidnBenchmark, oidnTest
#
# There are no headers: the `oidn` crate carries its own bindings and only links
# -lOpenImageDenoise from $OIDN_DIR/lib. The libraries find each other through their own RPATH
# ($ORIGIN/../lib); a program linked against them must find libOpenImageDenoise.so.2 itself
# (an rpath to $OIDN_DIR/lib, or LD_LIBRARY_PATH): see denoise/README.md.
#
# Idempotent: a finished install leaves a stamp holding the wheel's SHA-256; a second run that
# finds it only prints the prefix (no pip, no network). The wheel is cached under
# $FURNACE_CACHE (default ~/.cache/furnace) so a changed prefix does not download again.
# Messages go to stderr; stdout is only the OIDN_DIR line.
set -euo pipefail

version=2.5.1
wheel=pyoidn-$version.0-py3-none-manylinux2014_x86_64.whl
# SHA-256 of $wheel as published on PyPI (checked after every download and before unpacking).
wheel_sha256=32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e

cache=${FURNACE_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/furnace}
prefix=${1:-${OIDN_PREFIX:-$cache/oidn-$version}}
# Absolute: it becomes OIDN_DIR, and an rpath.
prefix=$(realpath -m -- "$prefix")
stamp=$prefix/.furnace-oidn-install

say() { echo "install-oidn: $*" >&2; }

if [ "$(uname -s)-$(uname -m)" != Linux-x86_64 ]; then
  say "the pyoidn wheel is for Linux x86_64 only; elsewhere use Intel's release package"
  say "(https://github.com/RenderKit/oidn/releases/tag/v$version) and point OIDN_DIR at it"
  exit 1
fi

# --- fast path: already installed from this very wheel --------------------------------------------
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$wheel_sha256" ] &&
  [ -e "$prefix/lib/libOpenImageDenoise.so.$version" ] && [ -e "$prefix/lib/libOpenImageDenoise.so" ]; then
  echo "$prefix"
  exit 0
fi

# --- the wheel ------------------------------------------------------------------------------------
wheels=$cache/wheels
mkdir -p "$wheels"
sha_ok() { [ -f "$1" ] && [ "$(sha256sum "$1" | cut -d' ' -f1)" = "$wheel_sha256" ]; }
if ! sha_ok "$wheels/$wheel"; then
  rm -f "$wheels/$wheel"
  if ! python3 -m pip --version >/dev/null 2>&1; then
    say "error: needs pip to download the pyoidn wheel (Debian: apt-get install python3-pip)"
    exit 1
  fi
  say "downloading pyoidn==$version with pip into $wheels"
  # `pip download` installs nothing (so it is allowed on an externally-managed Debian Python).
  # The only file of this release for Linux x86_64 is the py3-none-manylinux2014 wheel (glibc
  # 2.17+), which pip takes on any such host; --only-binary keeps it from building anything.
  python3 -m pip download --quiet --no-deps --only-binary=:all: --dest "$wheels" "pyoidn==$version" >&2
  if ! sha_ok "$wheels/$wheel"; then
    say "error: $wheels/$wheel is missing or its SHA-256 is not $wheel_sha256"
    exit 1
  fi
fi

# --- unpack pyoidn/oidn/{lib,bin} into a fresh directory, then move it into place -----------------
say "unpacking into $prefix"
mkdir -p "$(dirname "$prefix")"
staging=$(mktemp -d "$prefix.tmp.XXXXXX")
trap 'rm -rf "$staging"' EXIT
python3 - "$wheels/$wheel" "$staging" <<'PY'
import os, sys, zipfile
wheel, dest = sys.argv[1], sys.argv[2]
root = "pyoidn/oidn/"
with zipfile.ZipFile(wheel) as z:
    for info in z.infolist():
        name = info.filename
        if not name.startswith(root) or name.endswith("/"):
            continue
        rel = name[len(root):]
        if not (rel.startswith("lib/") or rel.startswith("bin/")) or ".." in rel.split("/"):
            continue
        out = os.path.join(dest, rel)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        with z.open(info) as src, open(out, "wb") as dst:
            while chunk := src.read(1 << 20):
                dst.write(chunk)
        # zipfile drops permissions; the wheel records them in the upper 16 bits.
        mode = (info.external_attr >> 16) & 0o777
        os.chmod(out, mode if mode else 0o644)
PY

# A wheel cannot hold symlinks, so libfoo.so, libfoo.so.N and libfoo.so.N.M.P arrive as three
# identical copies (~80 MB of duplicates in all). Turn each copy that is byte-identical to a
# longer-versioned file into a symlink to it, as in Intel's own package (-> 178 MB becomes ~100).
(
  cd "$staging/lib"
  for f in *.so *.so.*; do
    [ -f "$f" ] && [ ! -L "$f" ] || continue
    # The longest name that starts with "$f." and has the same bytes.
    target=
    for g in "$f".*; do
      [ -f "$g" ] && [ ! -L "$g" ] && cmp -s "$f" "$g" || continue
      if [ -z "$target" ] || [ ${#g} -gt ${#target} ]; then target=$g; fi
    done
    if [ -n "$target" ]; then ln -sf "$target" "$f"; fi
  done
)

# Sanity check before taking the place of an old install.
for f in libOpenImageDenoise.so libOpenImageDenoise.so.2 libOpenImageDenoise.so.$version \
  libOpenImageDenoise_core.so.$version libOpenImageDenoise_device_cpu.so.$version libtbb.so.12; do
  if [ ! -e "$staging/lib/$f" ]; then
    say "error: the wheel has no lib/$f"
    exit 1
  fi
done

chmod 755 "$staging"  # mktemp made it 0700
echo "$wheel_sha256" >"$staging/.furnace-oidn-install"
rm -rf "$prefix"
mv "$staging" "$prefix"
trap - EXIT
say "installed OIDN $version ($(du -sh "$prefix" | cut -f1)); use OIDN_DIR=$prefix"
echo "$prefix"
