# groupwise: `make run` and `make test` set up everything they need (idempotently) and
# then do their job. Setup lands in .venv/ and is redone only when pyproject.toml changes.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMPS := .make-stamps
# The CPU build of PyTorch (pip takes it from local disk on the project's machines; an
# unpinned torch would pull gigabytes of CUDA wheels).
TORCH := torch==2.13.0

RUN_ENV ?= GridWorld
RUN_OUT ?= runs/quickstart

.PHONY: run test test-slow bench lint setup clean

run: $(STAMPS)/python
	$(BIN)/groupwise train --env $(RUN_ENV) --oracle pairwise --comparisons 60 --rounds 3 \
		--steps 30000 --seed 0 --out $(RUN_OUT) --resume

test: $(STAMPS)/dev
	$(BIN)/python -m pytest -n 2 --dist loadfile -q

test-slow: $(STAMPS)/dev
	$(BIN)/python -m pytest -m slow -q -s

bench: $(STAMPS)/dev
	$(BIN)/python -m benchmarks

lint: $(STAMPS)/dev
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks
	$(BIN)/mypy

setup: $(STAMPS)/dev

$(STAMPS)/system: scripts/system-deps.sh
	bash scripts/system-deps.sh
	@mkdir -p $(STAMPS) && touch $@

$(STAMPS)/venv:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q $(TORCH)
	@mkdir -p $(STAMPS) && touch $@

$(STAMPS)/python: $(STAMPS)/system $(STAMPS)/venv pyproject.toml
	$(BIN)/pip install -q -e .
	@touch $@

$(STAMPS)/dev: $(STAMPS)/python
	$(BIN)/pip install -q -e '.[dev]'
	@touch $@

clean:
	rm -rf $(VENV) $(STAMPS) runs
