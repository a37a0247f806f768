# kilnctl: every target creates .venv itself, so a fresh clone needs only Python 3.11.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench clean

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "need $(PYTHON) on PATH (or run: make PYTHON=python3 ...)"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(PY) -m kilnctl.demo --out out

test: $(STAMP)
	MPLBACKEND=Agg $(PY) -m pytest

bench: $(STAMP)
	MPLBACKEND=Agg $(PY) -m benchmarks.run

clean:
	rm -rf $(VENV) out
