# slipcycle — every target creates and uses .venv itself.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-$(shell sha1sum pyproject.toml | cut -c1-12)

.PHONY: demo test bench lint clean dist typecheck docs ccx

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[fe,cholmod,sweep,test,lint,topo,nastran,mesh,docs]"
	rm -f $(VENV)/.installed-* && touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/slipcycle demo --out demo-report
	@echo "Report: demo-report/report.md"

test: $(STAMP) ccx
	$(PY) -m pytest -n 2 --dist worksteal -q

# CalculiX (ccx 2.20, Debian/Ubuntu calculix-ccx) for the tests that run it, installed where
# the package manager can (as root, or with password-less sudo); never fails: without it
# those tests skip with the reason (and fail where CI is set, tests/calculix.py)
APT := env DEBIAN_FRONTEND=noninteractive apt-get -y -q
ccx:
	@command -v ccx >/dev/null 2>&1 || { \
	  if command -v apt-get >/dev/null 2>&1; then \
	    if [ "$$(id -u)" = 0 ]; then SUDO=; \
	    elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then SUDO="sudo -n"; \
	    else SUDO=none; fi; \
	    if [ "$$SUDO" != none ]; then \
	      $$SUDO $(APT) install calculix-ccx >/dev/null 2>&1 || \
	      { $$SUDO $(APT) update >/dev/null 2>&1 && \
	        $$SUDO $(APT) install calculix-ccx >/dev/null 2>&1; } || true; \
	    fi; \
	  fi; \
	  command -v ccx >/dev/null 2>&1 || echo "note: CalculiX (ccx) is not installed and" \
	    "could not be installed here; its tests skip (they fail where CI is set)"; }

bench: $(STAMP)
	$(PY) -m pip install --quiet -e ".[bench]"
	$(PY) benchmarks/run_all.py

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks

dist: $(STAMP)
	rm -rf dist
	$(PY) -m build --outdir dist .
	$(PY) -m twine check --strict dist/*

typecheck: $(STAMP)
	$(PY) -m mypy

# the site and its executed gallery (examples/gallery) in docs/_build/html; warnings fail
docs: $(STAMP)
	MPLBACKEND=Agg $(PY) -m sphinx -b html -W --keep-going -q docs docs/_build/html
	@echo "Docs: docs/_build/html/index.html"

clean:
	rm -rf $(VENV) demo-report .pytest_cache .hypothesis
	rm -rf docs/_build docs/auto_examples docs/api/generated docs/sg_execution_times.rst
