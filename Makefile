# kilnctl: every target creates .venv itself, so a fresh clone needs only Python 3.11.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test test-fast bench docs studies clean chromium

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "need $(PYTHON) on PATH (or run: make PYTHON=python3 ...)"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(PY) -m kilnctl.demo --out out

# the whole suite (what CI runs); test-fast skips the tests marked slow (each > ~10 s) while iterating.
# Two processes (pytest-xdist), each taking whole test files: CI has two cores
XDIST := -n 2 --dist loadfile
test: $(STAMP) chromium
	MPLBACKEND=Agg $(PY) -m pytest $(XDIST)

test-fast: $(STAMP) chromium
	MPLBACKEND=Agg $(PY) -m pytest $(XDIST) -m "not slow"

# headless Chromium for the test that loads each report page (tests/test_report_pages.py): installed when
# missing and we are root with apt-get; otherwise that test is skipped with the reason (never a failure here)
chromium:
	@if ! command -v chromium >/dev/null 2>&1 && ! command -v chromium-browser >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing Debian chromium for the report-page test"; \
	    (apt-get install -y -q chromium >/dev/null 2>&1 || (apt-get update -q >/dev/null 2>&1 && \
	     apt-get install -y -q chromium >/dev/null 2>&1)) || echo "could not install chromium: the browser test will be skipped"; \
	  else echo "chromium not found (not root or no apt-get): the browser test will be skipped"; fi; \
	fi

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
