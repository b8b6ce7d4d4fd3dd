#!/usr/bin/env bash
# Opt-in second engine: MuJoCo 3.11.0 (the version gymnasium-robotics 1.4.2 runs with), for
# `cargo build --features mujoco3`. Idempotent; `make setup-mujoco3` runs it after `make setup`.
#
# The library and its C headers come from the PyPI wheel mujoco==3.11.0 (cp311, manylinux 2.28,
# x86_64; the library inside does not depend on the Python version): downloaded with
# `python3 -m pip download --no-deps`, checked against a pinned sha256, and only
# mujoco/libmujoco.so.3.11.0, mujoco/include/mujoco/ and the licence unpacked into the
# git-ignored folder engines/mujoco-3.11.0/ (lib/, include/mujoco/, LICENSE), with
# lib/libmujoco.so -> libmujoco.so.3.11.0 for the linker. Binaries built with the feature find
# the library through an rpath to that folder (MUJOCO_DIR overrides the folder at build time).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VERSION="3.11.0"
WHEEL_NAME="mujoco-3.11.0-cp311-cp311-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl"
WHEEL_SHA256="16f94f05745225aaafb68016cbd2a1617f4af6b4bfca6c97d22c7b14e598d1f1"
DEST="$ROOT/engines/mujoco-$VERSION"
CACHE_DIR="${BLOCKPUZZLE_CACHE:-$HOME/.cache/blockpuzzle}"

log() { printf '[setup-mujoco3] %s\n' "$*"; }

if [ "$(uname -m)" != x86_64 ]; then
    log "the pinned wheel is for x86_64 Linux; on $(uname -m) build MuJoCo $VERSION yourself and set MUJOCO_DIR"
    exit 1
fi
if [ -f "$DEST/.sha256" ] && [ "$(cat "$DEST/.sha256")" = "$WHEEL_SHA256" ] \
    && [ -f "$DEST/lib/libmujoco.so.$VERSION" ] && [ -f "$DEST/include/mujoco/mujoco.h" ]; then
    log "MuJoCo $VERSION present in $DEST"
    exit 0
fi

. "$ROOT/scripts/pinned_wheel.sh"
fetch_pinned_wheel "$WHEEL_NAME" "$WHEEL_SHA256" "mujoco==$VERSION" --only-binary=:all: \
    --python-version 3.11 --implementation cp --abi cp311 --platform manylinux_2_28_x86_64

log "unpacking MuJoCo $VERSION into $DEST"
mkdir -p "$ROOT/engines"
TMP="$(mktemp -d "$ROOT/engines/.unpack.XXXXXX")"
chmod 755 "$TMP"
trap 'rm -rf "$TMP"' EXIT
python3 - "$WHEEL" "$TMP" "$VERSION" <<'PY'
import os, sys, zipfile
wheel, dest, version = sys.argv[1:4]
lib = f"mujoco/libmujoco.so.{version}"
n = 0
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        if name.endswith("/"):
            continue
        if name == lib:
            out = os.path.join(dest, "lib", os.path.basename(name))
        elif name.startswith("mujoco/include/mujoco/"):
            out = os.path.join(dest, "include", name[len("mujoco/include/"):])
        elif name.endswith(".dist-info/licenses/LICENSE"):
            out = os.path.join(dest, "LICENSE")
        else:
            continue
        os.makedirs(os.path.dirname(out), exist_ok=True)
        with z.open(name) as src, open(out, "wb") as dst:
            dst.write(src.read())
        n += 1
for need in (os.path.join(dest, "lib", os.path.basename(lib)), os.path.join(dest, "include/mujoco/mujoco.h")):
    if not os.path.exists(need):
        sys.exit(f"{need} not found in {wheel}")
print(f"[setup-mujoco3] unpacked {n} files")
PY
ln -s "libmujoco.so.$VERSION" "$TMP/lib/libmujoco.so"
echo "$WHEEL_SHA256" > "$TMP/.sha256"
rm -rf "$DEST"
mv "$TMP" "$DEST"
trap - EXIT
log "done"
