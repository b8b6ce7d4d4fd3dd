#!/usr/bin/env bash
# Makes (once each; skipped where the pins are there) the pinned Python venvs that `make test` uses
# after its Rust tests: .venv-zoo (scripts/zoo_python_check.sh), bench/.venv-fetchpush with the
# FetchPush-v4 reference it records (bench/align_fetchpush.sh --record), .venv-wheel
# (scripts/build_wheel.sh) and the wheel's test venv in $TMPDIR (scripts/python_check.sh).
# `make test` runs it beside `cargo test` (its log: target/python-venvs.log), where the downloads and
# the installs fill the time the build leaves a core idle; each script then finds its venv made.
# The installs compile no bytecode (`--no-compile`): Python compiles what the tests import, a small
# part of what is installed, and making the test venv took half the time (38 s against 18 s, both
# from pip's cache, on the 2-core AMD EPYC VM).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/zoo_python_check.sh" --venv
bash "$ROOT/bench/align_fetchpush.sh" --record
bash "$ROOT/scripts/build_wheel.sh" --venv
bash "$ROOT/scripts/python_check.sh" --venv
