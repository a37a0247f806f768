# kilnctl: every target creates .venv itself, so a fresh clone needs only Python 3.11.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench docs studies clean

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

# the documentation site, into out/site; --strict: any warning (broken link, missing page, docstring) fails
docs: $(STAMP)
	$(PY) -m mkdocs build --strict --site-dir out/site
	@echo "site: out/site/index.html"

# every study: the paper's (run_all.py --docs also renders docs/validation.md), then the others;
# their figures are copied to docs/figures/
studies: $(STAMP)
	MPLBACKEND=Agg $(PY) studies/run_all.py --docs
	@paper=" $$($(PY) -c "import runpy; print(' '.join(runpy.run_path('studies/run_all.py')['STUDIES']))") run_all "; \
	for f in studies/*.py; do \
	  n=$$(basename $$f .py); \
	  case "$$paper" in *" $$n "*) continue;; esac; \
	  echo "=== $$n"; MPLBACKEND=Agg $(PY) $$f || exit 1; \
	  if [ -f studies/out/$$n/$$n.png ]; then cp studies/out/$$n/$$n.png docs/figures/$$n.png; fi; \
	done

clean:
	rm -rf $(VENV) out
