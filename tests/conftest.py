"""Shared test helpers: loading a report page in headless Chromium; a record of the foreign plant; a failing script."""

import html
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

#: injected first into a copy of the page: records script errors, console.error calls and resources that fail
#: to load, then, after the load event, writes them with the images that did not decode into <pre id=__probe>
_PROBE = """<script>
window.__errs = [];
window.addEventListener('error', function (e) {
  var t = e.target;
  if (t && t.tagName) { window.__errs.push('resource failed: ' + t.tagName + ' ' + (t.src || t.href || '').slice(0, 60)); }
  else { window.__errs.push('error: ' + e.message); }
}, true);
(function () { var ce = console.error; console.error = function () {
  window.__errs.push('console.error: ' + Array.prototype.join.call(arguments, ' ')); ce.apply(console, arguments); }; })();
window.addEventListener('load', function () {
  var bad = [], imgs = document.images;
  for (var i = 0; i < imgs.length; i++) { if (!imgs[i].complete || imgs[i].naturalWidth === 0) bad.push(imgs[i].alt || 'image ' + i); }
  var d = document.createElement('pre'); d.id = '__probe';
  d.textContent = JSON.stringify({errors: window.__errs, broken_images: bad, images: imgs.length,
                                  page_width: document.documentElement.scrollWidth});
  document.body.appendChild(d);
});
</script>"""


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.fixture(scope="session")
def load_in_chromium(tmp_path_factory):
    """Return ``load(page) -> dict``: the page loaded in headless Chromium in a 1300 px window.

    The dict holds ``errors`` (script errors, console errors, resources that
    failed), ``broken_images``, ``images`` (count) and ``page_width`` [px].
    Skipped, with the reason, where Chromium is not installed.
    """
    exe = _chromium()
    if exe is None:
        pytest.skip("Chromium is not installed (Debian: apt-get install -y chromium; `make test` installs it "
                    "when run as root): the report pages are not checked in a browser")
    folder = tmp_path_factory.mktemp("chromium")

    def load(page):
        page = Path(page)
        text = page.read_text(encoding="utf-8")
        probed = folder / f"probed-{page.name}"
        probed.write_text(re.sub(r"<head>", "<head>" + _PROBE, text, count=1), encoding="utf-8")
        run = subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                              "--window-size=1300,900", "--virtual-time-budget=10000", "--dump-dom",
                              probed.as_uri()], capture_output=True, text=True, timeout=120)
        found = re.search(r'<pre id="__probe">(.*?)</pre>', run.stdout, re.S)
        assert found, f"Chromium did not load {page} (exit {run.returncode}): {run.stderr[-2000:]}"
        return json.loads(html.unescape(found.group(1)))

    return load


def foreign_stick_slip_record(folder, name, effects=None):
    """40 s at 10 Hz of the independently written plant (benchmarks/foreign_records.py) with torque-law
    stick-slip and ``effects`` (that plant's forms), written into ``folder`` and read back.

    Returns
    -------
    (Measurement, Parameters, dict)
        The record, the setup's parameters (which state the torque law) and the truth.
    """
    from benchmarks import foreign_records as fr
    from kilnctl.measure import load_setup, read_record

    spec = fr.PlantSpec(name, 40.0, 10.0, base=dict(fr._NUIS), setup_kiln=dict(friction_law="torque"),
                        effects=dict(effects or {}), layout="plain", h=1e-3)
    truth = fr.write_record(spec, folder)
    setup = load_setup(Path(folder) / f"{name}.toml")
    m = read_record(truth["csv"], setup.params, columns=truth["columns"])
    return m, setup.params, truth


def failing_script(folder, text: str) -> str:
    """Run ``text`` as a script (``folder/script.py``, with this Python) that must fail; return the last line
    of its standard error (the exception a user sees).  multiprocessing's resource tracker, a process of its
    own, may print a warning about leaked semaphores after the traceback when a pool broke (seen once in a
    clean-clone run): its lines are not the exception, and are skipped."""
    import sys

    script = Path(folder) / "script.py"
    script.write_text(text)
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=folder)
    assert run.returncode != 0, run.stdout[-2000:]
    lines = run.stderr.strip().splitlines()
    while len(lines) > 1 and "resource_tracker" in lines[-1]:
        lines.pop()
    return lines[-1]



def read_written_record(truth):
    """(params, measurement) of a record a red team's generator wrote (``truth["toml"]``, ``truth["csv"]``), read
    as ``kilnctl diagnose`` reads them: the setup with its gains resolved, the record against it."""
    from kilnctl.measure import load_setup, read_record
    from kilnctl.simulate import resolve_gains

    params = resolve_gains(load_setup(truth["toml"]).params)
    return params, read_record(truth["csv"], params)


def imported_packages(module) -> set:
    """Top-level names of the packages a module's source imports (an ast scan of every ``import`` and
    ``from ... import``, at any depth): what a red team's plant may use is checked against it."""
    import ast

    tree = ast.parse(Path(module.__file__).read_text())
    names = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    names |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
    return names
