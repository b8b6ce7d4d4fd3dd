# BlockPuzzle: the two commands a newcomer needs are `make train` and `make test`.
# Both run the idempotent set-up first (system packages + pinned Fetch assets).

CARGO ?= cargo
OUT ?= out

RUN ?= runs/BlocksTouch-v0-ddpg-s0
BP = $(CARGO) run --release --quiet --
# 0: all cores; 1 when two runs share the machine (libgomp's spinning threads collapse under contention).
TORCH_THREADS ?= 0
resume = $$(test -f $(1)/checkpoint.bin && echo --resume)

# Set-up, build, test, the main job, a demo and the benchmark. Every other experiment is a recipe
# file in experiments/ run with `blockpuzzle train --config FILE` (docs/training.md lists them).
.PHONY: setup setup-mujoco3 test-mujoco3 test-wheel test-fast lint demo test bench train build leaderboard

setup:
	bash scripts/setup.sh

build: setup
	$(CARGO) build --release

# A quick look: the scripted pushing controller on BlocksTouch-v0 at full difficulty,
# with a trajectory dump you can replay or render.
demo: build
	mkdir -p $(OUT)
	$(CARGO) run --release --quiet -- rollout --env BlocksTouch-v0 --policy scripted \
		--episodes 50 --seed 0 --out $(OUT)/BlocksTouch-v0-scripted.jsonl

# The Python venvs of the later steps are made (scripts/python_venvs.sh) while cargo builds and tests.
test: setup
	mkdir -p target && { bash scripts/python_venvs.sh > target/python-venvs.log 2>&1 & venvs=$$!; }; \
	$(CARGO) test --all && { wait $$venvs && cat target/python-venvs.log || { cat target/python-venvs.log; exit 1; }; }
	$(MAKE) lint
	bash scripts/zoo_python_check.sh
	$(MAKE) test-mujoco3
	$(MAKE) test-wheel

# Clippy on every target (library, binary, tests, examples) of the default build, warnings denied.
lint: setup
	$(CARGO) clippy --all-targets -- -D warnings

# The fast tier for the inner loop: the library's unit tests and the integration tests of the core
# (environments, tasks, rules, suites, the CLI, provenance), without the training runs, MPI and the
# bad-input rounds. `make test` (what CI runs) is the full suite.
FAST_SKIP = --skip learning:: --skip train:: --skip mpi:: --skip limits:: --skip aggrevated:: --skip set_network::
test-fast: setup
	$(CARGO) test --lib
	$(CARGO) test --test it -- $(FAST_SKIP)

# The opt-in second engine, MuJoCo 3.11.0 from its PyPI wheel (engines/mujoco-3.11.0, sha256-pinned):
# `cargo build --release --features mujoco3 --target-dir target/mujoco3` (its own target folder
# keeps the two builds apart).
setup-mujoco3: setup
	bash scripts/setup_mujoco3.sh
M3 = --profile release-test --no-default-features --features mujoco3,render --target-dir target/mujoco3
# The environment core, its tests and the renderer's on MuJoCo 3.11 (the training stack is engine-agnostic),
# in release code without LTO (Cargo.toml's `release-test` profile; in the default target folder with the
# test profile it took longer: its dependencies' features differ from the default build's anyway).
# With them the alignment with gymnasium-robotics FetchPush-v4 on the same engine (tests/it/align_mujoco3.rs),
# whose reference bench/align_fetchpush.sh records first (a venv with gymnasium-robotics and mujoco 3.11).
test-mujoco3: setup-mujoco3
	bash bench/align_fetchpush.sh --record
	BLOCKPUZZLE_ALIGN_REFERENCE=$(CURDIR)/target/align/fetchpush-v4.json $(CARGO) test $(M3) --lib --tests

# The Python sdist and, built from it, the manylinux_2_28 wheel (MuJoCo 3.11.0 from the mujoco wheel,
# the Fetch files from gymnasium-robotics'), installed into a fresh venv and tested away from the
# checkout; its CLI comparisons run the package's own `blockpuzzle` command (the Rust command line's
# code, on the same engine). Built without link-time optimisation (scripts/build_wheel.sh, the test
# profile): the same code in less time.
test-wheel: setup-mujoco3
	BLOCKPUZZLE_WHEEL_PROFILE=test bash scripts/python_check.sh

# Main job: DDPG with the paper's curriculum on BlocksTouch-v0 (2 workers); resumes $(RUN) if it exists.
train: build
	$(BP) train --config experiments/blocks-touch-ddpg.toml \
		--torch-threads $(TORCH_THREADS) --run-dir $(RUN) $(call resume,$(RUN))

# Throughput against gymnasium-robotics FetchPush-v4 (installs a Python venv under bench/).
bench: build
	bash bench/fetchpush.sh

# results/leaderboard.md from the suite results of both engines (scripts/generalization.sh writes them;
# tests/it/provenance.rs fails when the page is stale).
LEADERBOARD_RESULTS = results/generalization/mujoco-2.2.2 results/generalization/mujoco-3.11.0
leaderboard: build
	$(BP) results leaderboard $(LEADERBOARD_RESULTS) --out results/leaderboard.md
