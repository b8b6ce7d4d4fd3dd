#!/usr/bin/env bash
# Idempotent set-up for blockpuzzle on Debian (run as root, or with sudo available).
#
# 1. System packages (apt-get, no recommends): libmujoco-dev (MuJoCo 2.2.2), libclang-dev
#    (bindgen), libtorch-dev (libtorch 1.13.1 for tch) and libopenblas0-openmp; the BLAS and
#    LAPACK alternatives are pinned to the OpenMP OpenBLAS (the reference BLAS trains ~15x
#    slower, and the pthread OpenBLAS fights libtorch's OpenMP threads); libegl1, libegl-mesa0
#    and libgl1-mesa-dri (headless rendering through EGL with Mesa's software rasteriser); fonts-dejavu-core
#    for the labels of the training plots; python3-venv (the Python check of the zoo and the benchmarks' venvs).
#    chromium and chromium-driver: the browser test of `blockpuzzle serve` (tests/it/serve.rs) drives
#    Debian's headless Chromium through its ChromeDriver.
# 2. The Fetch robot assets from the PyPI wheel gymnasium-robotics==1.4.2: downloaded with
#    `python3 -m pip download --no-deps`, checked against a pinned sha256, and only the Fetch
#    files (robot.xml, shared.xml, stls/fetch/*.stl, textures/*) unpacked into the git-ignored
#    folder models/gymnasium_robotics/.
#
# Running it again does nothing that is already done.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WHEEL_NAME="gymnasium_robotics-1.4.2-py3-none-any.whl"
WHEEL_SHA256="a1743530431cb377e6b3b956d284bc96436fc68bac1648ef205054c178e7dc4b"
ASSETS_DIR="$ROOT/models/gymnasium_robotics"
CACHE_DIR="${BLOCKPUZZLE_CACHE:-$HOME/.cache/blockpuzzle}"
APT_PACKAGES=(libmujoco-dev libclang-dev libtorch-dev libopenblas0-openmp fonts-dejavu-core
    libegl1 libegl-mesa0 libgl1-mesa-dri python3-venv openmpi-bin libopenmpi-dev chromium chromium-driver)

log() { printf '[setup] %s\n' "$*"; }

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        log "not root and no sudo: install ${APT_PACKAGES[*]} yourself"; fi
fi

missing=()
for p in "${APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ! command -v python3 >/dev/null 2>&1; then missing+=(python3 python3-pip); fi
if [ "${#missing[@]}" -gt 0 ]; then
    log "installing system packages: ${missing[*]}"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
    log "system packages present: ${APT_PACKAGES[*]}"
fi

# BLAS/LAPACK used by libtorch: the OpenMP variant of OpenBLAS.
MA="$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo x86_64-linux-gnu)"
for lib in libblas.so.3 liblapack.so.3 libopenblas.so.0; do
    want="/usr/lib/$MA/openblas-openmp/$lib"
    if [ ! -e "$want" ]; then
        log "missing $want: reinstall libopenblas0-openmp"; exit 1
    fi
    if [ "$(readlink -f "/usr/lib/$MA/$lib")" != "$(readlink -f "$want")" ]; then
        log "selecting the OpenMP OpenBLAS for $lib"
        $SUDO update-alternatives --set "$lib-$MA" "$want" >/dev/null
    fi
    if [ "$(readlink -f "/usr/lib/$MA/$lib")" != "$(readlink -f "$want")" ]; then
        log "$lib does not resolve to the OpenMP OpenBLAS; run: update-alternatives --set $lib-$MA $want"; exit 1
    fi
done

if [ -f "$ASSETS_DIR/.sha256" ] && [ "$(cat "$ASSETS_DIR/.sha256")" = "$WHEEL_SHA256" ] \
    && [ -f "$ASSETS_DIR/fetch/robot.xml" ]; then
    log "Fetch assets present in $ASSETS_DIR"
    exit 0
fi

. "$ROOT/scripts/pinned_wheel.sh"
fetch_pinned_wheel "$WHEEL_NAME" "$WHEEL_SHA256" "gymnasium-robotics==1.4.2"

log "unpacking Fetch assets into $ASSETS_DIR"
TMP="$(mktemp -d "$ROOT/models/.unpack.XXXXXX")"
trap 'rm -rf "$TMP"' EXIT
python3 - "$WHEEL" "$TMP" <<'PY'
import sys, zipfile, os
wheel, dest = sys.argv[1], sys.argv[2]
prefix = "gymnasium_robotics/envs/assets/"
keep = ("fetch/robot.xml", "fetch/shared.xml", "stls/fetch/", "textures/")
n = 0
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        if not name.startswith(prefix) or name.endswith("/"):
            continue
        rel = name[len(prefix):]
        if not rel.startswith(keep):
            continue
        out = os.path.join(dest, rel)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        with z.open(name) as src, open(out, "wb") as dst:
            dst.write(src.read())
        n += 1
if n < 20:
    sys.exit(f"only {n} Fetch asset files found in {wheel}")
print(f"[setup] unpacked {n} files")
PY
echo "$WHEEL_SHA256" > "$TMP/.sha256"
rm -rf "$ASSETS_DIR"
mv "$TMP" "$ASSETS_DIR"
trap - EXIT
log "done"
