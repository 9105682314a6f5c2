# tillpath: the two commands a newcomer needs are `make run` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
HOST ?= 127.0.0.1
PORT ?= 8000

.PHONY: run test bench install install-dev lint typecheck clean screenshot messages

# Python environment, rebuilt when the declared dependencies change. `make run` needs only the
# runtime dependencies; the test and lint tools come with install-dev (`make test`).
$(BIN)/.installed: pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(BIN)/.installed-dev: $(BIN)/.installed
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $@

# Front-end libraries (Leaflet, Leaflet-Geoman) from the npm registry, exactly as locked.
node_modules/.installed: package.json package-lock.json
	npm ci --no-audit --no-fund --silent
	touch $@

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
	$(BIN)/python -m pytest

# The API benchmark loads the server with wrk (Debian), a real HTTP load generator.
bench: install-dev
	command -v wrk >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq wrk; }
	$(BIN)/python -m bench.run

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
