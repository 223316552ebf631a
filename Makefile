# The two commands a fresh machine needs are `make run` and `make test`; the rest are helpers.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
RUN_STAMP := $(VENV)/.run-installed
TEST_STAMP := $(VENV)/.test-installed

.PHONY: run test protos bench lint docs translations chromium ffmpeg nginx three clean

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(RUN_STAMP): pyproject.toml | $(VENV)/bin/python
	$(PY) -m pip install --quiet -e .
	touch $@

$(TEST_STAMP): pyproject.toml | $(VENV)/bin/python
	$(PY) -m pip install --quiet -e '.[test,docs]'
	touch $(RUN_STAMP) $@

# three.js draws the console's 3D views: from the npm registry at the version client_ui/static/vendor/package-lock.json
# pins, into node_modules there, served as static ES modules (an import map names them; no bundler, no build step).
VENDOR := client_ui/static/vendor
THREE_STAMP := $(VENDOR)/node_modules/.package-lock.json

three: $(THREE_STAMP)

$(THREE_STAMP): $(VENDOR)/package-lock.json
	@command -v npm >/dev/null 2>&1 || { \
	  echo "Installing Debian's nodejs and npm to fetch the browser's libraries"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq nodejs npm; }
	cd $(VENDOR) && npm ci --ignore-scripts --no-audit --no-fund
	touch $@

# ffmpeg encodes the demo lesson's video from the simulator, needed only until that video exists.
DEMO_VIDEO := instance/lessons/demo-first-moves.webm

run: $(RUN_STAMP) $(THREE_STAMP) $(if $(wildcard $(DEMO_VIDEO)),,ffmpeg)
	$(VENV)/bin/telelab up

# The suite's files run in parallel processes, one more than the logical cores and at most 4 (PostgreSQL's 100
# connections; tests/conftest.py caps them): most of a browser or robot test's time is a robot's or a page's real
# time, not the CPU's. From a clean clone on 2 cores, 3 processes took 1201 s (the machine 82 % busy), 2 took 1311 s
# (70 %); with 4 the first 1022 tests took 4112 s of their processes' time against 2524 with 3 (that run shared the
# machine with a benchmark for a few minutes, not enough for the gap). TEST_PROCESSES=0 runs them in this one.
# tests/conftest.py says what each process has of its own, which files share one, and why tests marked `alone` (their
# bounds are wall-clock times across processes) run while the others wait. Collection order is kept. The suite starts
# some hundreds of Python processes (skill servers, labs, writer children, benchmarks): with bytecode caching off in
# the environment (PYTHONDONTWRITEBYTECODE, as some images set it) each compiled the repository's modules again; on,
# the teaching and skill-server tests took 9 % less CPU.
TEST_PROCESSES ?= logical

test: $(TEST_STAMP) $(THREE_STAMP) chromium ffmpeg nginx
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy
	env -u PYTHONDONTWRITEBYTECODE $(PY) -m pytest -n $(TEST_PROCESSES) --dist loadfile --no-loadscope-reorder

# The browser tests run in Chromium's headless shell (Playwright's choice for headless), the benchmarks and the
# third-party-cookie test in the full browser: both are Debian's build of one Chromium release.
chromium:
	@command -v chromium >/dev/null 2>&1 && command -v chromium-headless-shell >/dev/null 2>&1 || { \
	  echo "Installing Debian's chromium and chromium-headless-shell for the browser tests"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq chromium chromium-headless-shell; }

ffmpeg:
	@command -v ffmpeg >/dev/null 2>&1 || { \
	  echo "Installing Debian's ffmpeg to record the demo lesson's video"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq ffmpeg; }

# The scale-out tests put Debian's nginx in front of `telelab up --workers 2`, as the README's deployment does.
nginx:
	@command -v nginx >/dev/null 2>&1 || test -x /usr/sbin/nginx || { \
	  echo "Installing Debian's nginx for the reverse-proxy tests"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq nginx; }

protos: $(TEST_STAMP)
	$(PY) protos/generate.py

# The browser benchmarks draw the console's views (three.js) in Debian's Chromium.
bench: $(TEST_STAMP) $(THREE_STAMP) chromium nginx
	$(VENV)/bin/telelab bench

# mypy checks what pyproject.toml's [tool.mypy] files lists (middleware, skill_server, protos).
lint: $(TEST_STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

# The documentation site (mkdocs.yml) into site/; --strict fails on a broken link, as tests/test_docs.py does.
docs: $(TEST_STAMP)
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict

# The language catalogues (docs/languages.md): the words of the code into each middleware/translations/<lang>/
# messages.po, then the compiled .mo and client_ui/static/lib/i18n/<lang>.js (both committed: a clone needs no build).
translations: $(RUN_STAMP)
	$(PY) -m middleware.translations.build

clean:
	rm -rf $(VENV) .pytest_cache site
