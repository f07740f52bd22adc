# groupwise: `make run` and `make test` set up everything they need (idempotently) and
# then do their job. Setup lands in .venv/ and web/node_modules/ and is redone only when
# pyproject.toml or web/package-lock.json changes; the web UI is rebuilt into the package
# (src/groupwise/static/, shipped as package data) when web/ changes.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMPS := .make-stamps
# npm steps run with the venv's bin/ first on PATH: it holds node and npm when the system's
# node is missing or too old for Vite 8 (scripts/install-node.sh); else the system's is used.
NPM := PATH="$(CURDIR)/$(BIN):$$PATH" npm

RUN_ENV ?= Hopper
RUN_DATA ?= data
WEB_BUILD := src/groupwise/static/index.html
WEB_SOURCES := $(shell find web/src web/index.html web/vite.config.ts web/tsconfig.json \
	-type f 2>/dev/null)

.PHONY: run test test-web test-slow bench lint setup web clean

# the interactive app on 127.0.0.1 (prints the URL); the session resumes on the next run
run: $(STAMPS)/python $(WEB_BUILD)
	$(BIN)/groupwise serve --env $(RUN_ENV) --data $(RUN_DATA)

# unit and integration tests two at a time, then the browser tests one at a time (each runs
# a server with its training worker and a Chromium: two at once only fight for the cores)
test: $(STAMPS)/dev $(WEB_BUILD) test-web
	GROUPWISE_PG_REQUIRED=1 $(BIN)/python -m pytest -n 2 --dist loadfile -q --durations=25 -m "not slow and not e2e"
	GROUPWISE_E2E_REQUIRED=1 $(BIN)/python -m pytest -q --durations=25 -m "not slow" tests/e2e

test-web: $(STAMPS)/web
	cd web && $(NPM) test

test-slow: $(STAMPS)/dev
	$(BIN)/python -m pytest -m slow -q -s

bench: $(STAMPS)/dev $(STAMPS)/web
	PATH="$(CURDIR)/$(BIN):$$PATH" $(BIN)/python -m benchmarks

lint: $(STAMPS)/dev
	$(BIN)/ruff check src tests benchmarks research
	$(BIN)/ruff format --check src tests benchmarks research
	$(BIN)/mypy
	$(BIN)/mypy research
	$(BIN)/python research/results_table.py check docs/results
	$(BIN)/python research/dmc_study.py --check docs/results/dmc/README.md

setup: $(STAMPS)/dev $(WEB_BUILD)

# the web UI alone, built into the package (scripts/check-install.sh)
web: $(WEB_BUILD)

$(STAMPS)/system: scripts/system-deps.sh
	bash scripts/system-deps.sh
	@mkdir -p $(STAMPS) && touch $@

# Debian's Chromium for the browser tests (never `playwright install`: no browser downloads)
# and Debian's PostgreSQL server for the storage and server tests on PostgreSQL
$(STAMPS)/system-dev: scripts/system-deps.sh
	bash scripts/system-deps.sh chromium postgresql
	@mkdir -p $(STAMPS) && touch $@

# the web UI's npm packages; node is checked first (order-only: a new check of node alone
# does not redo npm ci)
$(STAMPS)/web: web/package.json web/package-lock.json | $(STAMPS)/node
	cd web && $(NPM) ci --no-audit --no-fund
	@mkdir -p $(STAMPS) && touch $@

$(WEB_BUILD): $(STAMPS)/web $(WEB_SOURCES)
	cd web && $(NPM) run build

$(STAMPS)/node: scripts/install-node.sh | $(STAMPS)/venv
	bash scripts/install-node.sh $(VENV)
	@mkdir -p $(STAMPS) && touch $@

$(STAMPS)/venv:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	@mkdir -p $(STAMPS) && touch $@

# the CPU build of PyTorch (an unpinned torch would pull gigabytes of CUDA wheels)
$(STAMPS)/torch: scripts/install-torch.sh | $(STAMPS)/venv
	bash scripts/install-torch.sh $(BIN)/python
	@mkdir -p $(STAMPS) && touch $@

$(STAMPS)/python: $(STAMPS)/system $(STAMPS)/torch pyproject.toml
	$(BIN)/pip install -q -e '.[app,study]'
	@touch $@

$(STAMPS)/dev: $(STAMPS)/python $(STAMPS)/system-dev
	$(BIN)/pip install -q -e '.[dev,dmc,minari]'
	@touch $@

clean:
	rm -rf $(VENV) $(STAMPS) runs web/node_modules web/dist src/groupwise/static
