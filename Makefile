# BlockPuzzle: the two commands a newcomer needs are `make demo` and `make test`.
# Both run the idempotent set-up first (system packages + pinned Fetch assets).

CARGO ?= cargo
OUT ?= out

RUN ?= runs/BlocksTouch-v0-ddpg-s0

.PHONY: setup demo test bench train build clean-assets

setup:
	bash scripts/setup.sh

build: setup
	$(CARGO) build --release

# Main job: the scripted pushing controller on BlocksTouch-v0 at full difficulty,
# with a trajectory dump you can replay or render.
demo: build
	mkdir -p $(OUT)
	$(CARGO) run --release --quiet -- rollout --env BlocksTouch-v0 --policy scripted \
		--episodes 50 --seed 0 --out $(OUT)/BlocksTouch-v0-scripted.jsonl

test: setup
	$(CARGO) test --all

# DDPG with the paper's curriculum on BlocksTouch-v0 (2 workers); resumes $(RUN) if it exists.
train: build
	$(CARGO) run --release --quiet -- train --algo ddpg --env BlocksTouch-v0 --workers 2 --epochs 300 \
		--seed 0 --run-dir $(RUN) $$(test -f $(RUN)/checkpoint.bin && echo --resume)

# Throughput against gymnasium-robotics FetchPush-v4 (installs a Python venv under bench/).
bench: build
	bash bench/fetchpush.sh

clean-assets:
	rm -rf models/gymnasium_robotics
