"""The documentation: the site builds with --strict, and every docstring example runs.

The site check needs MkDocs and mkdocstrings (the ``docs`` extra, which the
``test`` extra includes); it is skipped, with the reason, only where they are
not installed.  The docstring examples are the package's own: each module's
examples run with doctest, one test per module.
"""

import doctest
import importlib
import importlib.util
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import kilnctl

ROOT = Path(__file__).resolve().parents[1]
#: modules that run something on import (the ``python -m kilnctl.cli`` and ``python -m kilnctl`` entry points)
NOT_IMPORTED = {"kilnctl.cli.__main__", "kilnctl.__main__"}
MODULES = sorted(m.name for m in pkgutil.walk_packages(kilnctl.__path__, "kilnctl.") if m.name not in NOT_IMPORTED)


def _has_prompt(name: str) -> bool:
    """True if the module's source shows a doctest prompt (checked without importing it)."""
    spec = importlib.util.find_spec(name)
    return spec is not None and spec.origin is not None and ">>>" in Path(spec.origin).read_text()


WITH_EXAMPLES = [m for m in MODULES if _has_prompt(m)]
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _examples(name):
    module = importlib.import_module(name)
    return [t for t in doctest.DocTestFinder(exclude_empty=True).find(module, name) if t.examples]


def test_the_package_has_docstring_examples():
    found = {name: sum(len(t.examples) for t in _examples(name)) for name in ("kilnctl", *WITH_EXAMPLES)}
    # a floor, so that a finder that silently finds nothing fails here
    assert sum(found.values()) >= 20, found
    assert found["kilnctl.sweep"] > 0 and found["kilnctl.params"] > 0


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_docstring_examples_run(name, monkeypatch, tmp_path):
    tests = _examples(name)
    if not tests:
        pytest.skip(f"{name} shows '>>>' only outside docstrings")
    monkeypatch.chdir(tmp_path)  # examples that write files write here
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for t in tests:
        runner.run(t)
    res = runner.summarize(verbose=False)
    assert res.failed == 0, f"{res.failed} of {res.attempted} docstring examples of {name} failed (output above)"


def _hooks():
    spec = importlib.util.spec_from_file_location("kilnctl_docs_hooks", ROOT / "docs" / "hooks.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_nav_leaves_out_pages_not_written_yet(tmp_path):
    (tmp_path / "a.md").write_text("# A")
    (tmp_path / "api").mkdir()
    (tmp_path / "api" / "x.md").write_text("# X")
    nav = [{"Home": "a.md"}, {"Tutorials": [{"T1": "missing.md"}, {"T2": "a.md"}]},
           {"Empty": [{"M": "gone.md"}]}, {"API": ["api/x.md", "api/y.md"]}, {"Site": "https://example.org"}]
    dropped = []
    out = _hooks()._prune(nav, tmp_path, dropped)
    assert out == [{"Home": "a.md"}, {"Tutorials": [{"T2": "a.md"}]}, {"API": ["api/x.md"]},
                   {"Site": "https://example.org"}]
    assert dropped == ["missing.md", "gone.md", "api/y.md"]


def test_site_builds_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="MkDocs is not installed: pip install 'kilnctl[docs]'")
    pytest.importorskip("mkdocstrings", reason="mkdocstrings is not installed: pip install 'kilnctl[docs]'")
    site = tmp_path / "site"
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"mkdocs build --strict failed:\n{proc.stderr[-6000:]}"
    assert (site / "index.html").is_file()
    quick = (site / "quickstart" / "index.html").read_text()
    assert "kilnctl sweep spec.toml" in quick
    api = (site / "api" / "sweep" / "index.html").read_text()
    # the API page is generated from the docstrings: a parameter documented with its unit
    assert "run_sweep" in api and "Simulated time of each start-up [s]" in api


def test_free_text_doctests_are_fenced_for_the_api_pages():
    spec = importlib.util.spec_from_file_location("kilnctl_griffe_doctest", ROOT / "docs" / "griffe_doctest.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    doc = 'Intro.\n\n>>> c.failing[0]["text"]\n\'x\'\n\nMore.\n\nExamples\n--------\n>>> 1 + 1\n2'
    out = mod.fence_doctests(doc)
    assert '```pycon\n>>> c.failing[0]["text"]\n\'x\'\n```' in out
    assert out.endswith("Examples\n--------\n>>> 1 + 1\n2")  # numpydoc sections are left to the parser


def test_pages_missing_from_the_nav_are_listed_under_more(tmp_path):
    for name in ("index.md", "new_page.md"):
        (tmp_path / name).write_text("# page")
    config = _hooks().on_config({"nav": [{"Home": "index.md"}, {"Soon": "later.md"}], "docs_dir": str(tmp_path)})
    assert config["nav"] == [{"Home": "index.md"}, {"More": ["new_page.md"]}]
