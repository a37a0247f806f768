"""The installable package: `python -m build` gives a wheel and an sdist, and the wheel works outside the repository.

The wheel is installed into a fresh virtual environment in a temporary folder; its dependencies are lent from
the environment running the tests (a path file, so no network and no second copy of CasADi), and kilnctl
itself must come from the wheel: the repository is neither on the path nor the working folder.
"""

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from pathlib import Path

import pytest

import kilnctl

ROOT = Path(__file__).resolve().parents[1]
VERSION = kilnctl.__version__
#: files outside Python modules that kilnctl needs at run time
DATA = ("kilnctl/data/example_record.csv", "kilnctl/data/example_setup.toml", "kilnctl/model/rosenbrock.c")

# Not marked slow, so that `make test` runs it (issue 14): build, install, design and a diagnosis of two
# candidates took 97 s under a load of 6-8 on 2 cores (29 s of CPU).


def _run(argv, **kw):
    r = subprocess.run(argv, capture_output=True, text=True, timeout=600, **kw)
    assert r.returncode == 0, f"{' '.join(map(str, argv))} failed:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    return r


@pytest.fixture(scope="module")
def dist(tmp_path_factory):
    """Build sdist and wheel (the wheel from the sdist, as `python -m build` does) from a copy of the sources."""
    pytest.importorskip("build", reason="the test extra installs 'build'")
    tmp = tmp_path_factory.mktemp("pkg")
    src = tmp / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", ".venv", "__pycache__", "*.egg-info", "build", "dist", "out", ".kilnctl_cache", ".pytest_cache",
        ".tmp-*"))
    out = tmp / "dist"
    # --no-isolation: the build backend comes from this environment (setuptools>=77 is in the test extra)
    _run([sys.executable, "-m", "build", "--no-isolation", "--outdir", str(out), str(src)])
    wheels, sdists = list(out.glob("*.whl")), list(out.glob("*.tar.gz"))
    assert [w.name for w in wheels] == [f"kilnctl-{VERSION}-py3-none-any.whl"]
    assert [s.name for s in sdists] == [f"kilnctl-{VERSION}.tar.gz"]
    return wheels[0], sdists[0]


def test_wheel_and_sdist_carry_the_data_the_c_source_and_one_version(dist):
    wheel, sdist = dist
    names = set(zipfile.ZipFile(wheel).namelist())
    assert set(DATA) <= names
    meta = zipfile.ZipFile(wheel).read(f"kilnctl-{VERSION}.dist-info/METADATA").decode()
    assert f"\nVersion: {VERSION}\n" in meta  # the version of kilnctl/__init__.py, the one place it is written
    entry = zipfile.ZipFile(wheel).read(f"kilnctl-{VERSION}.dist-info/entry_points.txt").decode()
    assert "kilnctl = kilnctl.cli:run" in entry
    # PEP 639: the licence is named by its SPDX expression and its text travels in both distributions
    assert "\nLicense-Expression: BSD-3-Clause\n" in meta and "\nLicense-File: LICENSE\n" in meta
    assert f"kilnctl-{VERSION}.dist-info/licenses/LICENSE" in names
    members = {m.split("/", 1)[1] for m in tarfile.open(sdist).getnames() if "/" in m}
    assert set(DATA) | {"pyproject.toml", "README.md", "CHANGELOG.md", "LICENSE", "Makefile",
                         "tests/test_package.py"} <= members


def test_the_wheel_runs_design_and_a_diagnosis_outside_the_repository(dist, tmp_path):
    wheel, _ = dist
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)])
    py = venv / "bin" / "python"
    site = Path(_run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]).stdout.strip())
    # lend the dependencies: a path entry, not a site folder, so this environment's editable kilnctl is not seen
    deps = sorted({sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]})
    (site / "_kilnctl_test_deps.pth").write_text("\n".join(deps) + "\n")
    _run([sys.executable, "-m", "pip", "--python", str(py), "install", "--quiet", "--no-deps", "--no-index",
          str(wheel)])
    work = tmp_path / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(KILNCTL_CACHE=str(tmp_path / "cache"), MPLBACKEND="Agg", PYTHONNOUSERSITE="1")

    def kilnctl_(*argv):
        return _run([str(venv / "bin" / "kilnctl"), *argv], cwd=work, env=env)

    where = _run([str(py), "-c", "import kilnctl, kilnctl.measure as m; print(kilnctl.__file__); "
                  "print(*m.example_paths(), sep='\\n')"], cwd=work, env=env).stdout.split()
    assert all(Path(p).is_relative_to(venv) for p in where), where  # kilnctl and its data come from the wheel
    assert kilnctl_("--version").stdout.strip() == f"kilnctl {VERSION}"

    # truth: the design of this source tree, computed in this process
    from kilnctl import Parameters
    from kilnctl.design import design_pid

    d = design_pid(Parameters())
    got = json.loads(kilnctl_("design", "--json").stdout)
    assert (got["kp"], got["ki"], got["kd"]) == pytest.approx((d.gains.k_p, d.gains.k_I, d.gains.k_D), rel=1e-9)

    rec, setup = where[1], where[2]
    out = json.loads(kilnctl_("diagnose", "--data", rec, "--config", setup, "--candidates",
                              "second_motor,speed_sensor_lag", "--calibrate", "mu_c,m_v", "--json").stdout)
    # truth (kilnctl/measure/synthetic.py, tests/test_measure_example.py): the example hides a second motor
    assert out["selected"] == ["second_motor"]
    assert out["final"]["current_A"] > out["baseline"]["current_A"] + 1.0  # fit % of the current rises
    if shutil.which(os.environ.get("CC", "gcc")) and not os.environ.get("KILNCTL_NO_COMPILE"):
        # the stepper was compiled from the wheel's C source into the fresh cache
        assert list((tmp_path / "cache").rglob("*.so")), "no compiled plant in the new cache"
