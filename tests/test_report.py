"""kilnctl.report: the paper-comparison table and the signal measures, against analytic signals."""

import json
import math

import numpy as np
import pytest

from kilnctl.errors import KilnctlError
from kilnctl.report import PaperTable, oscillation, settle_time, window_peak


def test_settle_time_of_a_decaying_exponential():
    # truth: exp(-t) enters the band |y| <= 0.05 for good at t = ln 20
    t = np.linspace(0, 10, 100001)
    assert settle_time(t, np.exp(-t), 0.05, final=0.0) == pytest.approx(math.log(20), abs=2e-4)
    assert settle_time(t, np.sin(t), 0.05, final=0.0) is None  # outside the band at the end


def test_oscillation_of_a_sine():
    # truth: 2 + 3 sin(2 pi 0.37 t) has peak-to-peak 6 and frequency 0.37 Hz
    t = np.linspace(0, 40, 40001)
    ptp, f = oscillation(t, 2 + 3 * np.sin(2 * np.pi * 0.37 * t), t_from=10.0)
    assert ptp == pytest.approx(6.0, rel=1e-4)
    assert f == pytest.approx(0.37, rel=1e-4)
    assert oscillation(t, t, 10.0)[1] is None  # a ramp has no mean crossings upward twice


def test_window_peak():
    t = np.linspace(0, 4, 4001)
    y = -np.sin(np.pi * t / 2)  # |y| peaks at t = 1 and t = 3
    assert window_peak(t, y, 0.0, 2.0) == pytest.approx((1.0, 1.0))
    with pytest.raises(KilnctlError, match="no sample"):
        window_peak(t, y, 5.0, 6.0)


def test_table_markdown_json_and_verdicts(tmp_path):
    tab = PaperTable("figX", "a check")
    tab.add("current | final", "620 A", "842 A", "differs", "Table 1")
    with pytest.raises(KilnctlError, match="verdict"):
        tab.add("x", "1", "2", "maybe")
    md = tab.to_markdown().splitlines()
    assert md[0].startswith("| quantity | paper reports | kilnctl gives | verdict")
    assert md[2] == "| current \\| final | 620 A | 842 A | differs | Table 1 |"  # pipe escaped
    tab.write(tmp_path)
    data = json.loads((tmp_path / "table.json").read_text())
    assert data["rows"][0]["kilnctl"] == "842 A" and data["study"] == "figX"
    assert "note: Table 1" in tab.to_text()


def test_outputs_get_the_mode_of_any_new_file(tmp_path):
    # truth: a file created by open() in the same folder under the same umask (figures and reports were 0600,
    # other outputs 0644: issue 14)
    import os
    import stat

    from kilnctl.files import write_atomic

    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    out = write_atomic(tmp_path / "report.html", "<p>x</p>")
    assert stat.S_IMODE(os.stat(out).st_mode) == stat.S_IMODE(os.stat(plain).st_mode)
