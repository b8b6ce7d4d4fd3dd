# BlockPuzzle: the two commands a newcomer needs are `make train` and `make test`.
# Both run the idempotent set-up first (system packages + pinned Fetch assets).

CARGO ?= cargo
OUT ?= out

RUN ?= runs/BlocksTouch-v0-ddpg-s0
# The AggreVaTeD expert: the zoo's 2-block DDPG (or a run's policy, e.g. EXPERT=$(RUN)/policy.json).
EXPERT ?= BlocksTouch-v0-ddpg
EPISODES ?= 1000
BP = $(CARGO) run --release --quiet --
BIN = target/release/blockpuzzle
NP ?= 20
# mpirun as root needs --allow-run-as-root; --oversubscribe lets NP exceed the cores (slowly).
MPIRUN ?= mpirun $$(test "$$(id -u)" = 0 && echo --allow-run-as-root) --oversubscribe $(MPIFLAGS)
resume = $$(test -f $(1)/checkpoint.bin && echo --resume)

.PHONY: setup setup-mujoco3 test-mujoco3 demo test bench bench-mpi train build clean-assets ddpg3 ddpg3-paper aggrevated aggrevated-adv pggd table ddpg-task task-rates study validate expert-snapshots filmstrip aggrevated-weak

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

test: setup
	$(CARGO) test --all
	bash scripts/zoo_python_check.sh
	bash scripts/python_check.sh
	$(MAKE) test-mujoco3

# The opt-in second engine, MuJoCo 3.11.0 from its PyPI wheel (engines/mujoco-3.11.0, sha256-pinned):
# `cargo build --release --features mujoco3 --target-dir target/mujoco3` (its own target folder
# keeps the two builds apart).
setup-mujoco3: setup
	bash scripts/setup_mujoco3.sh
M3 = --release --no-default-features --features mujoco3,render --target-dir target/mujoco3
# The environment core, its tests and the renderer's on MuJoCo 3.11 (the training stack is engine-agnostic).
# With them the alignment with gymnasium-robotics FetchPush-v4 on the same engine (tests/align_mujoco3.rs),
# whose reference bench/align_fetchpush.sh records first (a venv with gymnasium-robotics and mujoco 3.11).
test-mujoco3: setup-mujoco3
	bash bench/align_fetchpush.sh --record
	BLOCKPUZZLE_ALIGN_REFERENCE=$(CURDIR)/target/align/fetchpush-v4.json $(CARGO) test $(M3) --lib --tests

# Main job: DDPG with the paper's curriculum on BlocksTouch-v0 (2 workers); resumes $(RUN) if it exists.
train: build
	$(BP) train --config experiments/blocks-touch-ddpg.toml \
		--torch-threads $(TORCH_THREADS) --run-dir $(RUN) $(call resume,$(RUN))

# The paper's results table, one target per row (each resumes its run directory); the recipes are
# the files in experiments/ (`blockpuzzle train --config FILE`, flags on the command line win):
#   DDPG (2 blocks) = `make train` above, shipped in the zoo as the AggreVaTeD expert ($(EXPERT));
#   DDPG (3 blocks) on BlocksChoose-v0;
ddpg3: build
	$(BP) train --config experiments/ddpg3.toml --torch-threads $(TORCH_THREADS) \
		--run-dir runs/BlocksChoose-v0-ddpg-s0 $(call resume,runs/BlocksChoose-v0-ddpg-s0)
#   the paper's own configuration, 20 MPI workers (one process each, `make ddpg3-paper NP=20`;
#   MPIFLAGS="--hostfile examples/mpi/hostfile" spreads it over machines, see docs/training.md);
ddpg3-paper: build
	$(MPIRUN) -np $(NP) $(BIN) train --config experiments/ddpg3-paper.toml \
		--run-dir runs/BlocksChoose-v0-ddpg-np$(NP)-s0 $(call resume,runs/BlocksChoose-v0-ddpg-np$(NP)-s0)
#   The headline study (results/headline.md): DDPG variants on BlocksChoose-v0, 2 workers,
#   `make study VARIANT=ours EPOCHS=100 SEED=0` (each resumes runs/study-VARIANT-sSEED). The
#   baseline is the paper's configuration: seed 0 is `make ddpg3` itself (its first epochs).
VARIANT ?= ours
EPOCHS ?= 100
SEED ?= 0
# 0: all cores; 1 when two runs share the machine (libgomp's spinning threads collapse under contention).
TORCH_THREADS ?= 0
# The recipes' updates use bfloat16 products (`--precision bf16`), which need AMX or AVX512-BF16
# (`blockpuzzle info`: "bf16 updates yes"); PRECISION=f32 runs the same recipe in float32 on any CPU,
# in its own run directory (runs/study-VARIANT-f32-sSEED).
PRECISION ?= bf16
# The variants are the recipes in experiments/study/ (one file each).
STUDY_FILE = experiments/study/$(VARIANT).toml
STUDY_VARIANTS = $(sort $(basename $(notdir $(wildcard experiments/study/*.toml))))
study_bf16 = $(shell grep -qs '^precision *= *"bf16"' $(STUDY_FILE) && echo yes)
study_prec = $(if $(study_bf16),$(if $(filter f32,$(PRECISION)),--precision f32))
#   FROM=RUN_DIR branches that run instead of starting afresh (`train --branch-from`: its latest
#   checkpoint, with this variant's draws or update count) into runs/study-VARIANT-branched-sSEED.
#   RANKS=2 runs the 2 workers as 2 MPI ranks of 1 worker (torch threads 1 each): the same computation
#   bit for bit, faster when the run has the 2 cores to itself (results/mpi.md); resume a run with
#   the RANKS it started with.
RANKS ?= 1
study_dir = runs/study-$(VARIANT)$(if $(FROM),-branched)$(1)-s$(SEED)
STUDY_DIR = $(call study_dir,$(if $(study_prec),-f32))
study_launch = $(if $(filter 2,$(RANKS)),$(MPIRUN) -np 2 $(BIN) train --workers 1 --torch-threads 1,$(BP) train --workers 2 --torch-threads $(TORCH_THREADS))
study: build
	@test -n "$(filter $(VARIANT),$(STUDY_VARIANTS))" || \
		{ echo "VARIANT must be one of: $(STUDY_VARIANTS)"; exit 2; }
	@test -n "$(filter $(PRECISION),bf16 f32)" || { echo "PRECISION must be bf16 or f32"; exit 2; }
	@test -n "$(filter $(RANKS),1 2)" || { echo "RANKS must be 1 (one process of 2 workers) or 2 (mpirun)"; exit 2; }
	@test -z "$(study_bf16)" -o "$(PRECISION)" = f32 || $(BIN) info | grep -q "^bf16 updates yes" || \
		{ echo "VARIANT=$(VARIANT) updates in bfloat16, and this CPU has no AMX or AVX512-BF16 for it: add PRECISION=f32 to run the same recipe in float32 ($(call study_dir,-f32))"; exit 2; }
	$(study_launch) --config $(STUDY_FILE) --epochs $(EPOCHS) --seed $(SEED) \
		$(study_prec) --run-dir $(STUDY_DIR) \
		$$(test -f $(STUDY_DIR)/checkpoint.bin && echo --resume || echo $(if $(FROM),--branch-from $(FROM)))
#   Validation of a run's snapshots, the study's selection data (never the test seeds): 200 episodes
#   from seed 2,000,000, Normal and Challenge, with outcome counts, e.g.
#   `make validate RUN=runs/study-ours-nol2-s0 AT="40 100"` -> results/headline/validation/
AT ?= 100
validate: build
	mkdir -p results/headline/validation
	for e in $(AT); do for c in "" --challenge; do \
		$(BP) eval --checkpoint $(RUN)/snapshots/epoch-$$(printf %04d $$e).json --episodes 200 --seed 2000000 $$c \
			--out results/headline/validation/$(notdir $(RUN))-epoch$$e$$c.json || exit 1; done; done
#   PGGD + AggreVaTeD on BlocksChoose-v0 with the 2-block expert (beta0 = 0, t0 = 50);
aggrevated: build
	$(BP) train --config experiments/aggrevated.toml --expert $(EXPERT) --torch-threads $(TORCH_THREADS) \
		--run-dir runs/BlocksChoose-v0-pggd-aggrevated-s0 $(call resume,runs/BlocksChoose-v0-pggd-aggrevated-s0)
#   the snapshots of the BlocksTouch-v0 run as experts: each one's grey-removed success on
#   BlocksChoose-v0 on validation seeds (200 episodes from 2,000,000; the test seeds stay unused),
#   to pick the earlier expert whose success is near the paper's 0.44 (results/aggrevated-weak.md);
expert-snapshots: build
	mkdir -p $(OUT)/expert-snapshots
	for f in $(RUN)/snapshots/epoch-*.json; do \
		$(BP) eval --checkpoint $$f --env BlocksChoose-v0 --episodes 200 --seed 2000000 \
			--out $(OUT)/expert-snapshots/$$(basename $$f); done
#   PGGD + AggreVaTeD from that weaker expert (zoo: BlocksTouch-v0-ddpg-epoch60), to see whether
#   the learner overtakes a weaker expert as the paper's did;
aggrevated-weak: build
	$(BP) train --config experiments/aggrevated-weak.toml --torch-threads $(TORCH_THREADS) \
		--run-dir runs/BlocksChoose-v0-pggd-aggrevated-weak-s0 $(call resume,runs/BlocksChoose-v0-pggd-aggrevated-weak-s0)
#   the same with the paper's descent direction, the expert critic's advantage (not a table row);
aggrevated-adv: build
	$(BP) train --config experiments/aggrevated-adv.toml --expert $(EXPERT) --torch-threads $(TORCH_THREADS) \
		--run-dir runs/BlocksChoose-v0-pggd-aggrevated-adv-s0 $(call resume,runs/BlocksChoose-v0-pggd-aggrevated-adv-s0)
#   PGGD alone on BlocksChoose-v0;
pggd: build
	$(BP) train --config experiments/pggd.toml --torch-threads $(TORCH_THREADS) \
		--run-dir runs/BlocksChoose-v0-pggd-s0 $(call resume,runs/BlocksChoose-v0-pggd-s0)
#   and the table itself (rows whose run is missing say so).
table: build
	$(BP) table --expert $(EXPERT) --ddpg runs/BlocksChoose-v0-ddpg-s0 \
		--pggd runs/BlocksChoose-v0-pggd-aggrevated-s0 --pggd-alone runs/BlocksChoose-v0-pggd-s0 \
		--episodes $(EPISODES) --out results/table.md

# A filmstrip of a policy (zoo name, file or run directory) in the challenge distribution:
# `make filmstrip POLICY=BlocksChoose-v0-ddpg-ours EPISODE=1000000` -> $(OUT)/filmstrip-POLICY.png
# (seen from the robot's left, where the arm hides the blocks least).
POLICY ?= BlocksChoose-v0-ddpg
EPISODE ?= 1000000
CAMERA ?= --distance 1.1 --elevation -45 --azimuth 270 --width 360 --height 360
filmstrip: build
	mkdir -p $(OUT)
	$(BP) render --policy $(POLICY) --env BlocksChoose-v0 --challenge --seed $(EPISODE) --filmstrip 6 \
		$(CAMERA) --out $(OUT)/filmstrip-$(notdir $(POLICY)).png

# Throughput against gymnasium-robotics FetchPush-v4 (installs a Python venv under bench/).
bench: build
	bash bench/fetchpush.sh

# Training across MPI ranks against threads, and the 20-rank projection (results/mpi.md).
bench-mpi: build
	bash bench/mpi_scaling.sh

clean-assets:
	rm -rf models/gymnasium_robotics

# The task framework's new tasks (results/tasks.md): DDPG with the paper's hyperparameters and the
# task file's curriculum, one worker and one torch thread so that four runs share two cores;
# `make ddpg-task TASK=ToppleTower-v0` (resumes runs/$(TASK)-ddpg-s0 if it exists).
TASK ?= ReachAvoid-v0
ddpg-task: build
	$(BP) train --config experiments/ddpg-task.toml --env $(TASK) \
		--run-dir runs/$(TASK)-ddpg-s0 $(call resume,runs/$(TASK)-ddpg-s0)
# Scripted and random success rates of a task at its evaluation level (200 episodes each).
task-rates: build
	mkdir -p $(OUT)
	for p in scripted random; do $(BP) rollout --env $(TASK) --policy $$p --episodes 200 --seed 0 \
		--out $(OUT)/$(TASK)-$$p.jsonl; done
