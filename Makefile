# The two entry points of the README. Both create .venv at the repository root.
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed
BROWSER_STAMP := $(VENV)/.installed-browser
CHROMIUM := /usr/bin/chromium

.PHONY: run test check test-browser test-docs test-fuzz lint setup clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip
	$(VENV)/bin/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

run: $(STAMP)
	$(VENV)/bin/hybridtable reproduce --out-dir out/reproduce --json out/reproduce/reproduce.json --force

# The whole suite, one pytest worker per CPU (pytest-xdist; a test file stays
# on one worker, so its module fixtures are computed once). WORKERS=1 runs it
# in one process.
WORKERS ?= auto
test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	MPLBACKEND=Agg $(VENV)/bin/python -m pytest -q -n $(WORKERS) --dist loadfile

# The inner loop: lint and every test not marked slow or cluster (under 90 s).
check: $(STAMP)
	$(VENV)/bin/ruff check .
	MPLBACKEND=Agg $(VENV)/bin/python -m pytest -q -x -n $(WORKERS) --dist load \
	  -m "not slow and not cluster and not browser and not docs and not fuzz"

$(BROWSER_STAMP): $(STAMP)
	$(VENV)/bin/python -m pip install --quiet -e '.[test,browser]'
	touch $(BROWSER_STAMP)

# The HTML reports opened in headless chromium: Debian's package (installed here
# if missing), driven by playwright; no browser is ever downloaded. A missing
# browser is a failure here, not a skip.
test-browser: $(BROWSER_STAMP)
	@if [ ! -x $(CHROMIUM) ]; then \
	  if [ "$$(id -u)" -eq 0 ]; then SUDO=; else SUDO=sudo; fi; \
	  $$SUDO apt-get update && \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y chromium chromium-driver; \
	fi
	HYBRIDTABLE_REQUIRE_BROWSER=1 MPLBACKEND=Agg $(VENV)/bin/python -m pytest -q -m browser

# Every sh and python block of README.md and docs/*.md, run as written in a
# copy of the repository with nothing beside it (tests/test_docs.py); one
# document per pytest worker, each in its own copy.
test-docs: $(STAMP)
	MPLBACKEND=Agg $(VENV)/bin/python -m pytest -q -n $(WORKERS) --dist load -m docs tests/test_docs.py

# The hostile corpus of the newer surfaces (tests/fuzz/surfaces.py: plug-ins,
# sweep specs and --resume, model files, 6-DoF scenarios, CoR tables, outputs),
# written apart from the code; about 10 minutes on two cores. Not in CI yet:
# some of its cases still fail (the closing note of issue 34 lists them).
test-fuzz: $(STAMP)
	MPLBACKEND=Agg $(VENV)/bin/python -m pytest -q -m fuzz tests/fuzz/test_surfaces.py

clean:
	rm -rf $(VENV) out
