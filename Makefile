# The whole set-up on a fresh machine with Python 3.11: `make demo` and `make test`.
# Both install exactly the locked environment (requirements-lock.txt: every package, pinned with its
# hashes) into .venv, and refresh it when the lock changes. uv installs it; uv itself is installed
# by pip into .tools at the version below, which the lock pins too.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
LOCK := requirements-lock.txt
TOOLS := .tools
UV := $(TOOLS)/bin/uv
UV_VERSION := $(shell sed -n 's/^uv==\([^ ]*\).*/\1/p' $(LOCK))
# uv never downloads a Python of its own here: the machine's python3 is the one.
export UV_PYTHON_DOWNLOADS := never
# The shared motion-capture clips (../shared beside the checkout), for the 3D scene step of the demo.
MOCAP ?= ../shared/data/mocap

.PHONY: demo test test-latest lock lint bench fuzz browser validator jscheck docs clean

$(UV): $(LOCK)
	test -x $(TOOLS)/bin/python || $(PYTHON) -m venv $(TOOLS)
	$(TOOLS)/bin/python -m pip install --quiet --disable-pip-version-check 'uv==$(UV_VERSION)'
	touch $(UV)

# Exactly the lock: packages it does not list are removed, every file is checked against its hash.
# The project itself is installed editable, built by the locked setuptools.
$(STAMP): $(LOCK) pyproject.toml $(UV)
	$(UV) venv --quiet --allow-existing --python $(PYTHON) $(VENV)
	$(UV) pip sync --quiet --python $(BIN)/python --require-hashes $(LOCK)
	$(UV) pip install --quiet --python $(BIN)/python --no-deps --no-build-isolation -e .
	touch $(STAMP)

# The lock, made from pyproject.toml's ranges (every extra) for CPython 3.11 on Linux, with the
# hashes of every file of each pinned version. Pins the ranges still allow are kept, so an unchanged
# pyproject.toml gives the same lock; UPGRADE=1 moves every pin to the newest allowed version.
lock: $(UV)
	$(UV) pip compile pyproject.toml --all-extras --generate-hashes --python-version 3.11 \
	  --python-platform linux --no-emit-index-url --no-emit-find-links --quiet \
	  $(if $(UPGRADE),--upgrade) -o $(LOCK)

demo: $(STAMP)
	mkdir -p demo
	$(BIN)/toonmotion sample -o demo/hero.png --skeleton demo/hero.json --keys demo/keys.json
	$(BIN)/toonmotion rig demo/hero.png --skeleton demo/hero.json -o demo/hero
	$(BIN)/toonmotion show demo/hero -o demo/overview.png
	$(BIN)/toonmotion depth demo/hero right_elbow=1 right_hand=1
	$(BIN)/toonmotion animate demo/hero demo/keys.json -o demo/demo.gif
	$(BIN)/toonmotion animate demo/hero demo/keys.json -o demo/demo.mp4
	$(BIN)/toonmotion animate demo/hero demo/keys.json -o demo/demo_exaggerated.gif --exaggerate 1.5
	$(BIN)/toonmotion animate demo/hero demo/keys.json -o demo/frames --save-frame-motion demo/motion.json
	$(BIN)/toonmotion export demo/hero demo/keys.json -o demo/demo.glb
	$(BIN)/toonmotion export demo/hero demo/keys.json -o demo/demo_sheet.json --format sheet
	$(BIN)/toonmotion export demo/hero demo/keys.json -o demo/spine/demo.json --format spine
	$(BIN)/toonmotion export demo/hero demo/keys.json -o demo/demo.webm
	$(BIN)/toonmotion lift demo/motion.json --prior $(MOCAP)/cmu_16_07_jump.bvh --frames demo/frames \
	  --view 0,0 -o demo/proxy.json --glb demo/proxy.glb
	$(BIN)/toonmotion scene demo/proxy.json --project demo/hero --keys demo/keys.json \
	  --balloon right_hand --balls left_foot,right_foot -o demo/demo_scene.mp4

test: $(STAMP) browser validator jscheck docs
	$(BIN)/ruff check src tests benchmarks docs/hooks
	$(BIN)/mypy
	$(BIN)/python -m pytest

# The documentation site (mkdocs.yml: the guides in docs/ and the API reference read from the
# docstrings) into build/site; --strict fails on a broken link or a reference that does not resolve.
export NO_MKDOCS_2_WARNING := 1
docs: $(STAMP)
	$(BIN)/mkdocs build --strict --quiet

# The suite against the newest versions pyproject.toml allows, with no lock: what a user who installs
# the library into an environment of their own gets today. A throw-away environment in .venv-latest.
LATEST := .venv-latest

test-latest: $(UV) browser validator
	rm -rf $(LATEST)
	$(UV) venv --quiet --python $(PYTHON) $(LATEST)
	$(UV) pip install --quiet --python $(LATEST)/bin/python --refresh -e '.[dev,docs]'
	$(UV) pip list --python $(LATEST)/bin/python --format freeze > $(LATEST)/versions.txt
	$(LATEST)/bin/mkdocs build --strict --quiet --site-dir $(LATEST)/site
	$(LATEST)/bin/python -m pytest

# The editor's browser tests drive Debian's Chromium (Playwright); installed here when missing and
# run as root (as CI is). Elsewhere the tests skip without it, except under CI=true.
browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ]; then \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	  else echo "the editor's browser tests need Debian's chromium: sudo apt-get install chromium"; fi; }

# The glTF export's tests run the Khronos glTF validator (npm's gltf-validator, pinned by package.json
# and package-lock.json into node_modules/). Node.js and npm are installed here when missing and run as
# root (as CI is); elsewhere those tests skip without them, except under CI=true.
validator:
	@command -v npm >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ]; then \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq nodejs npm >/dev/null; \
	  else echo "the glTF validator tests need Node.js and npm: sudo apt-get install nodejs npm"; fi; }
	@if command -v npm >/dev/null 2>&1 && [ ! node_modules/.package-lock.json -nt package-lock.json ]; then \
	  npm ci --no-audit --no-fund --loglevel=error; fi

# The editor's page (src/toonmotion/web/static): ESLint's recommended rules and TypeScript's checker
# over its JSDoc types (checkJs, tsconfig.json), both pinned in package.json; 0 problems. Without npm
# (not root, not installed) it is skipped with a word, except under CI=true.
jscheck: validator
	@if command -v npx >/dev/null 2>&1; then \
	  npx --no-install eslint src/toonmotion/web/static && npx --no-install tsc -p tsconfig.json; \
	elif [ "$$CI" = true ]; then echo "the page's checks need Node.js and npm"; exit 1; \
	else echo "skipping the page's checks (ESLint, TypeScript): they need Node.js and npm"; fi

# The long profile of the generated-bad-input suite (tests/fuzz): FUZZ_EXAMPLES cases per test;
# the runs per format and outcome go to fuzz-report.json.
FUZZ_EXAMPLES ?= 400

fuzz: $(STAMP)
	TOONMOTION_FUZZ_PROFILE=long TOONMOTION_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(BIN)/python -m pytest -p no:cacheprovider tests/fuzz
	cat fuzz-report.json

# The shared Animated Drawings folders, animated and tracked by benchmarks/track_footage.py.
DRAWINGS := $(wildcard ../shared/data/drawings/*/char_cfg.yaml)
DRAWINGS := $(DRAWINGS:/char_cfg.yaml=)

bench: $(STAMP)
	$(BIN)/python benchmarks/rig.py
	$(BIN)/python benchmarks/deform.py
	$(BIN)/python benchmarks/edit.py
	$(BIN)/python benchmarks/track.py
	$(BIN)/python benchmarks/track.py --style flat
	$(BIN)/python benchmarks/track_footage.py
	$(if $(DRAWINGS),$(BIN)/python benchmarks/track_footage.py --drawings $(DRAWINGS))
	$(BIN)/python benchmarks/editor.py
	$(BIN)/python benchmarks/proxy3d.py
	$(BIN)/python benchmarks/scene3d.py
	$(BIN)/python benchmarks/view_search.py
	$(BIN)/python benchmarks/batch.py

clean:
	rm -rf $(VENV) $(LATEST) $(TOOLS) demo node_modules dist
