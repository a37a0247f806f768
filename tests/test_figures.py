"""The figures a new user meets first: axes labelled with quantity and unit, no interactive hints in
saved files, the record named by its file name, the design's margins and the requirement violations
stated.

Truths: the design's own condition reports (computed apart from the plot) for the margins; the
parameter locus' data for where damping falls below the requirement.
"""

import re

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from kilnctl import Parameters  # noqa: E402
from kilnctl.design import design_pid  # noqa: E402
from kilnctl.figures import record_name, save_figure  # noqa: E402

UNIT = re.compile(r"\[[^\]]+\]")


@pytest.fixture(scope="module")
def design():
    return design_pid(Parameters())


def _texts(fig):
    return [t.get_text() for t in fig.findobj(matplotlib.text.Text)]


def _main_axes(fig):
    return [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]


def _check_labels(fig):
    for ax in _main_axes(fig):
        assert UNIT.search(ax.get_ylabel()), f"y axis without a unit: {ax.get_ylabel()!r} ({ax.get_title()!r})"
        shared = ax.get_shared_x_axes().get_siblings(ax)
        assert any(UNIT.search(a.get_xlabel()) for a in shared), f"x axis without a unit ({ax.get_title()!r})"


def test_record_name_is_the_file_name():
    assert record_name("/data/plant/run 3.csv") == "run 3.csv"
    assert record_name("data/run 3.csv") == "run 3.csv"
    assert record_name("C:\\logs\\kiln2.csv") == "kiln2.csv"
    assert record_name("/data/plant/run3") == "run3"
    assert record_name("synthetic") == "synthetic"
    assert record_name("drift 0.25 A/s") == "drift 0.25 A/s"  # a label, not a path


def test_root_locus_states_its_margins_and_has_no_interactive_hint(design, tmp_path):
    fig = design.locus().plot()
    _check_labels(fig)
    text = "\n".join(_texts(fig))
    assert "click" not in text and "interactive" not in text
    req = design.requirements
    for cond, r in design.reports.items():
        # truth: the design's condition report (poles computed by the design, not by the plot)
        lines = text.splitlines()
        i = next(k for k, t in enumerate(lines) if t.startswith(f"{cond}: min"))
        line = lines[i] + lines[i + 1]
        dz = r.zeta_min_all - req.zeta_min
        dw = req.wn_max - r.dominant_wn
        assert f"{r.zeta_min_all:.3f}" in line and f"margin {dz if abs(dz) >= 5e-4 else 0.0:.3f}" in line
        assert f"{r.dominant_wn:.2f} rad/s" in line and f"margin {dw if abs(dw) >= 5e-3 else 0.0:.2f}" in line
    save_figure(fig, tmp_path / "rl.png")


def test_parameter_locus_marks_where_damping_is_too_low(design):
    data = design.parameter_locus()
    fig = data.plot()
    _check_labels(fig)
    text = "\n".join(_texts(fig))
    z = data.pair_zeta("stick")
    bad = data.values[z < design.requirements.zeta_min] * 1e-3  # [t]
    # truth: the locus data; the plot names the burden masses where zeta < zeta_min
    assert bad.size and f"{bad.min():.0f} to {bad.max():.0f} t" in text
    ax_d = fig.axes[1]
    assert ax_d.get_ylim()[0] == 0.0  # the dominant pole's axis starts at zero


def test_verify_figure_labels_every_line(tmp_path):
    from kilnctl.verify import verify

    v = verify(Parameters(), "macro", 20.0)
    fig = v.plot()
    _check_labels(fig)
    for ax in fig.axes:
        # every line is in the legend, or drawn in the style of one that is (a repeated event of a kind)
        styles = {(ln.get_color(), ln.get_linestyle()) for ln in ax.get_lines() if not ln.get_label().startswith("_")}
        for ln in ax.get_lines():
            assert not ln.get_label().startswith("_") or (ln.get_color(), ln.get_linestyle()) in styles
    assert not [t for t in _texts(fig) if t == "breakaway"]  # no stacked event labels


def test_comparison_figure_names_the_record_and_labels_its_axes():
    from kilnctl.measure import compare, example_paths, load_setup, read_csv

    record, setup_path = example_paths()
    setup = load_setup(setup_path)
    c = compare(read_csv(record, setup.params), setup.params, t0=setup.options.get("t0_s"))
    fig = c.plot()
    _check_labels(fig)
    title = fig._suptitle.get_text()
    assert title.startswith("example_record.csv") and "/" not in title
    assert any("Dashed vertical lines" in t for t in _texts(fig))  # the caption explains lines and shading
    assert np.isfinite(c.channels["current_A"].fit)


def test_comparison_legends_stay_inside_their_panels_with_a_long_final_structure():
    """A diagnosis' final structure of three effects named in the legend ran over the next panels.

    Truth: the drawn geometry (the renderer's extents of each legend and of its axes), not the label text.
    """
    from kilnctl.measure import compare, example_paths, load_setup, read_csv

    record, setup_path = example_paths()
    setup = load_setup(setup_path)
    c = compare(read_csv(record, setup.params), setup.params, t0=setup.options.get("t0_s"))
    long = "final: base + speed_sensor_lag (second-order form), motor_coulomb_friction, viscous_drag"
    fig = c.plot(compare_with=c, labels=("calibrated base", long))
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    r = canvas.get_renderer()
    legends = [(ax, ax.get_legend()) for ax in fig.axes if ax.get_legend() is not None]
    assert len(legends) == 4  # the first row's four panels
    for ax, leg in legends:
        box, frame = leg.get_window_extent(r), ax.get_window_extent(r)
        assert frame.x0 - 1 <= box.x0 and box.x1 <= frame.x1 + 1, ax.get_title()
    assert any("viscous_drag" in t.get_text() for t in legends[0][1].get_texts())  # named in full where wide
