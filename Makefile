# tillpath: the two commands a newcomer needs are `make run` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
HOST ?= 127.0.0.1
PORT ?= 8000

.PHONY: run test bench soak install lint typecheck clean screenshot

# Python environment, rebuilt when the declared dependencies change.
$(BIN)/.installed: pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@

# Front-end libraries (Leaflet, Leaflet-Geoman) from the npm registry, exactly as locked.
node_modules/.installed: package.json package-lock.json
	npm ci --no-audit --no-fund --silent
	touch $@

install: $(BIN)/.installed node_modules/.installed

run: install
	$(BIN)/tillpath serve --host $(HOST) --port $(PORT)

test: install
	scripts/ensure-chromium
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy
	$(BIN)/python -m pytest

# The API benchmark loads the server with wrk (Debian), a real HTTP load generator.
bench: install
	command -v wrk >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq wrk; }
	$(BIN)/python -m bench.run

# The soak and fault suite for longer (make test runs it for a few seconds a test): a mixed
# load on a real server on SQLite and PostgreSQL (TILLPATH_TEST_DATABASE_URL), killed and
# restarted, and schemathesis with every phase. SOAK_S: seconds of load per test.
SOAK_S ?= 120
soak: install
	TILLPATH_SOAK_S=$(SOAK_S) $(BIN)/python -m pytest -m soak -p no:cacheprovider -s tests/soak

lint: install
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

typecheck: install
	$(BIN)/mypy

clean:
	rm -rf $(VENV) node_modules .pytest_cache .hypothesis .mypy_cache

screenshot: install
	$(BIN)/python scripts/screenshot.py
