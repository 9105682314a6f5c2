# tillpath: the two commands a newcomer needs are `make run` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
HOST ?= 127.0.0.1
PORT ?= 8000
# make test runs the tests in this many processes (pytest-xdist), a test file to a process: one
# per CPU, at most 4 (each starts servers and browsers of its own). TEST_WORKERS=0: one process.
TEST_WORKERS ?= $(shell n=$$(nproc 2>/dev/null || echo 1); [ $$n -gt 4 ] && n=4; echo $$n)

.PHONY: run test bench soak install install-dev lint typecheck clean screenshot messages lock wheel

# Python environment, exactly as locked (every transitive package pinned), rebuilt when the lock
# changes; the project itself is installed without resolving anything. `make run` needs only the
# runtime lock (requirements.lock); the test and lint tools come with install-dev
# (requirements-dev.lock, `make test`).
$(BIN)/.installed: pyproject.toml requirements.lock
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements.lock
	$(BIN)/python -m pip install --quiet --no-deps -e .
	@echo "compiling the planner's numba kernels into planner/__pycache__ (once, about a minute)"
	$(BIN)/python -c "from planner.warm_up import warm_up; warm_up()"
	touch $@

$(BIN)/.installed-dev: $(BIN)/.installed requirements-dev.lock
	$(BIN)/python -m pip install --quiet -r requirements-dev.lock
	touch $@

# Front-end libraries (Leaflet, Leaflet-Geoman, Swagger UI) from the npm registry, exactly as
# locked; no install scripts (swagger-ui-dist's @scarf/scarf would report the install).
node_modules/.installed: package.json package-lock.json
	SCARF_ANALYTICS=false npm ci --no-audit --no-fund --silent --ignore-scripts
	touch $@

# Refresh both lock files from pyproject.toml (after adding or bumping a dependency there).
# uv resolves for every platform (--universal), for the oldest Python we support.
UV_COMPILE = $(BIN)/uv pip compile pyproject.toml --universal --python-version 3.11 \
	--custom-compile-command "make lock" --quiet
lock: $(BIN)/.installed-dev
	$(UV_COMPILE) -o requirements.lock
	$(UV_COMPILE) --extra dev -o requirements-dev.lock

# A wheel that serves the page from any directory: templates, static files, the npm libraries,
# migrations and alembic.ini inside it (see setup.py).
wheel: install
	rm -rf build dist
	$(BIN)/python -m pip wheel --quiet --no-deps -w dist .

install: $(BIN)/.installed node_modules/.installed

install-dev: install $(BIN)/.installed-dev

# HOST=0.0.0.0 to reach the page from a phone on the farm network; CERTFILE and KEYFILE for
# HTTPS, which the phone's GPS needs (README: "From a phone in the field").
run: install
	$(BIN)/tillpath serve --host $(HOST) --port $(PORT) $(if $(CERTFILE),--certfile $(CERTFILE)) $(if $(KEYFILE),--keyfile $(KEYFILE))

test: install-dev
	scripts/ensure-chromium
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/mypy
	$(BIN)/python -m pytest -n $(TEST_WORKERS) --dist loadfile

# The API benchmark loads the server with wrk (Debian), a real HTTP load generator.
bench: install-dev
	command -v wrk >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq wrk; }
	$(BIN)/python -m bench.run

# The soak and fault suite for longer (make test runs it for a few seconds a test): a mixed
# load on a real server on SQLite and PostgreSQL (TILLPATH_TEST_DATABASE_URL), killed and
# restarted, and schemathesis with every phase. SOAK_S: seconds of load per test.
SOAK_S ?= 120
soak: install-dev
	TILLPATH_SOAK_S=$(SOAK_S) $(BIN)/python -m pytest -m soak -p no:cacheprovider -s tests/soak

lint: install-dev
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

typecheck: install-dev
	$(BIN)/mypy

clean:
	rm -rf $(VENV) node_modules .pytest_cache .hypothesis .mypy_cache

screenshot: install-dev
	$(BIN)/python scripts/screenshot.py
	$(BIN)/python scripts/screenshot.py --phone --lang en -o docs/phone-en.png
	$(BIN)/python scripts/screenshot.py --phone --lang id -o docs/phone-id.png

# After wrapping a new string in _() / t(): extract every string and add the new ones to the
# Indonesian catalog (then translate them there; tests/app/test_i18n.py fails until you do).
messages: install-dev
	$(BIN)/pybabel extract -F babel.cfg -k t -k _ -k tn:1,2 -k N_ --no-location --sort-output \
		--omit-header -o $(VENV)/messages.pot .
	$(BIN)/pybabel update -i $(VENV)/messages.pot -d app/locale -D messages \
		--ignore-obsolete --no-fuzzy-matching -w 100
