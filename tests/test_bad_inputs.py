"""Every bad input is one clear error: exit code 2, the parameter or file named, no traceback.

A table of bad configuration files, CLI options, sweep specs and measurement records, each run
in-process through ``kilnctl.cli.main`` (argparse's own refusals exit with 2 through SystemExit).
Independent truth: the case's own definition -- each row says which name the message must
contain (the offending parameter, option, key or file).
"""

from __future__ import annotations

import traceback

import pytest

from kilnctl.cli import main
from kilnctl.errors import ParameterError

RECORD_HEAD = "time_s,current_A,speed_rpm\n"
GOOD_RECORD = RECORD_HEAD + "".join(f"{0.02 * i:.2f},{10.0 + i},{1.0 * i}\n" for i in range(50))

# --- configuration files given to `kilnctl params --config` ----------------------------------------
# (id, TOML text or bytes, names the message must contain)
CONFIGS = [
    ("bom", b"\xef\xbb\xbf[kiln]\nm_v = 6e5\n", ["byte-order mark", "cfg.toml"]),
    ("latin1", "[kiln]\n# Bürde\nm_v = 6e5\n".encode("latin-1"), ["UTF-8", "cfg.toml"]),
    ("syntax", "[kiln\nm_v = 6e5\n", ["not a valid TOML", "line"]),
    ("syntax_value", "[kiln]\nm_v = = 6\n", ["not a valid TOML"]),
    ("duplicate_key", "[kiln]\nm_v = 6e5\nm_v = 7e5\n", ["not a valid TOML"]),
    ("unknown_section", "[kilnn]\nm_v = 6e5\n", ["[kilnn]", "kiln"]),
    ("unknown_key", "[kiln]\nm_vv = 6e5\n", ["m_vv", "m_v"]),
    ("unknown_top_key", "foo = 1\n", ["foo"]),
    ("string_number", "[kiln]\nm_v = \"heavy\"\n", ["m_v", "number"]),
    ("bool_number", "[kiln]\nm_v = true\n", ["m_v", "number"]),
    ("list_number", "[kiln]\nm_v = [1, 2]\n", ["m_v", "number"]),
    ("date_number", "[kiln]\nm_v = 1979-05-27\n", ["m_v", "number"]),
    ("subtable", "[kiln.m_v]\nx = 1\n", ["m_v"]),
    ("nan", "[kiln]\nm_v = nan\n", ["m_v", "finite"]),
    ("inf", "[motor]\nR_a = inf\n", ["R_a", "finite"]),
    ("negative", "[motor]\nR_a = -0.01\n", ["R_a", "> 0"]),
    ("zero_inertia", "[motor]\nJ_m = 0\n", ["J_m", "> 0"]),
    ("negative_friction", "[kiln]\nmu_c = -0.1\n", ["mu_c", ">= 0"]),
    ("negative_gain", "[controller]\nk_D = -1.0\n", ["k_D", ">= 0"]),
    ("fraction", "[gear]\ngap_0 = 1.5\n", ["gap_0", "[0, 1]"]),
    ("huge_resistance", "[motor]\nR_a = 1e300\n", ["R_a", "times its default"]),
    ("huge_mass", "[kiln]\nm_v = 1e300\n", ["m_v", "times its default"]),
    ("tiny_inductance", "[motor]\nL_a = 1e-20\n", ["L_a", "times its default"]),
    ("backlash_in_mm", "[gear]\ndelta_x = 8\n", ["delta_x", "0.008"]),
    ("backlash_beyond_pitch", "[gear]\ndelta_x = 0.2\n", ["delta_x", "pitch"]),
    ("mu_c_above_mu_s", "[kiln]\nmu_c = 0.6\nmu_s = 0.5\n", ["mu_c", "mu_s"]),
    ("bad_option", "[kiln]\nJ_e_mode = \"tabel\"\n", ["J_e_mode", "'table'"]),
    ("number_option", "[kiln]\nfriction_law = 3\n", ["friction_law"]),
    ("pinion_larger", "[gear]\nR_p = 5.0\n", ["R_o", "R_p"]),
    ("ratio_too_small", "[gear]\nn = 5.0\n", ["'n'", "R_o/R_p"]),
    ("table_J_e", "[kiln]\nJ_e_mode = \"table\"\nJ_e = 1e6\n", ["J_e", "J_v"]),
    ("bad_gains_option", "[controller]\ngains = \"auto\"\n", ["gains", "'design'"]),
]

# --- implausible values refused with --strict (warnings without it) ---------------------------------
STRICT = [
    ("mu_percent", "[kiln]\nmu_c = 40\nmu_s = 51\n", ["mu_s", "0.51"]),
    ("mass_in_tonnes", "[kiln]\nm_v = 580\n", ["m_v", "580000"]),
    ("inertia_in_tonnes", "[kiln]\nJ_o = 6978\n", ["J_o", "6.978e+06"]),
    ("radius_in_mm", "[kiln]\nR = 2170\n", ["R =", "2.17"]),
]

# --- command lines (placeholders: {dir} a folder, {file} a plain file, {cfg} a good config) ----------
OPTIONS = [
    ("params_dir", ["params", "--config", "{dir}"], ["folder"]),
    ("simulate_dir", ["simulate", "--config", "{dir}"], ["folder"]),
    ("design_dir", ["design", "--config", "{dir}"], ["folder"]),
    ("verify_dir", ["verify", "--config", "{dir}"], ["folder"]),
    ("optimize_dir", ["optimize-ramp", "--config", "{dir}"], ["folder"]),
    ("params_missing", ["params", "--config", "{dir}/nope.toml"], ["nope.toml", "no such"]),
    ("simulate_t_end_zero", ["simulate", "--t-end", "0"], ["t_end"]),
    ("simulate_t_end_negative", ["simulate", "--t-end", "-5"], ["t_end"]),
    ("simulate_t_end_nan", ["simulate", "--t-end", "nan"], ["t_end"]),
    ("simulate_t_end_inf", ["simulate", "--t-end", "inf"], ["t_end"]),
    ("simulate_t_end_1e9", ["simulate", "--t-end", "1e9"], ["--t-end", "--max-samples"]),
    ("simulate_t_end_1e5", ["simulate", "--t-end", "1e5"], ["--t-end", "--max-samples"]),
    ("simulate_t_end_text", ["simulate", "--t-end", "long"], ["--t-end"]),
    ("simulate_model", ["simulate", "--model", "mezzo"], ["--model"]),
    ("simulate_law", ["simulate", "--law", "coulomb"], ["--law"]),
    ("simulate_effects_empty", ["simulate", "--effects", "second_motor,,x"], ["--effects"]),
    ("simulate_effects_unknown", ["simulate", "--effects", "second_motr"], ["second_motr", "second_motor"]),
    ("simulate_csv_dir", ["simulate", "--csv", "{dir}"], ["--csv", "folder"]),
    ("simulate_csv_is_config", ["simulate", "--config", "{cfg}", "--csv", "{cfg}"], ["--csv", "--config"]),
    ("simulate_plot_format", ["simulate", "--plot", "{dir}/x.xyz"], ["--plot", "xyz"]),
    ("simulate_same_outputs", ["simulate", "--csv", "{dir}/a.png", "--plot", "{dir}/a.png"], ["--csv", "--plot"]),
    ("simulate_max_samples_zero", ["simulate", "--max-samples", "0"], ["max_samples", "--max-samples"]),
    ("simulate_max_samples_text", ["simulate", "--max-samples", "many"], ["--max-samples"]),
    ("design_zeta_negative", ["design", "--zeta", "-0.1"], ["zeta_min"]),
    ("design_zeta_above_one", ["design", "--zeta", "1.5"], ["zeta_min"]),
    ("design_zeta_nan", ["design", "--zeta", "nan"], ["zeta_min"]),
    ("design_settling_zero", ["design", "--settling-time", "0"], ["settling_time_max"]),
    ("design_overshoot_negative", ["design", "--overshoot", "-1"], ["overshoot_max"]),
    ("design_wn_zero", ["design", "--wn-max", "0"], ["wn_max"]),
    ("design_plot_dir", ["design", "--plot", "{dir}"], ["--plot", "folder"]),
    ("design_plot_format", ["design", "--plot", "{dir}/d.xyz"], ["--plot", "xyz"]),
    ("design_infeasible", ["design", "--settling-time", "0.01"], ["settling_time_max"]),
    ("verify_t_end", ["verify", "--t-end", "-1"], ["t_end"]),
    ("verify_model", ["verify", "--model", "nano"], ["--model"]),
    ("verify_plot_dir", ["verify", "--plot", "{dir}"], ["--plot", "folder"]),
    ("verify_plot_format", ["verify", "--plot", "{dir}/v.xyz"], ["--plot", "xyz"]),
    ("verify_plot_is_config", ["verify", "--config", "{cfg}", "--plot", "{cfg}"], ["--plot", "--config"]),
    ("optimize_profile", ["optimize-ramp", "--profile", "zigzag"], ["profile"]),
    ("optimize_pwl_zero", ["optimize-ramp", "--profile", "pwl:0"], ["pwl"]),
    ("optimize_pwl_huge", ["optimize-ramp", "--profile", "pwl:999"], ["pwl"]),
    ("optimize_t_max", ["optimize-ramp", "--t-max", "-3"], ["t_max"]),
    ("optimize_max_rate_zero", ["optimize-ramp", "--max-rate", "0"], ["max_rate"]),
    ("optimize_max_rate_huge", ["optimize-ramp", "--max-rate", "1e9"], ["max_rate"]),
    ("optimize_max_rate_nan", ["optimize-ramp", "--max-rate", "nan"], ["max_rate", "rpm/s"]),  # said "seconds"
    ("optimize_plot_format", ["optimize-ramp", "--plot", "{dir}/o.xyz"], ["--plot", "xyz"]),
    ("unknown_command", ["simluate"], ["simluate"]),
    ("compare_data_missing", ["compare", "--data", "{dir}/none.csv"], ["none.csv"]),
    ("compare_data_dir", ["compare", "--data", "{dir}"], ["folder"]),
    ("compare_report_file", ["compare", "--data", "{rec}", "--report", "{file}"], ["--report", "folder"]),
    ("diagnose_report_file", ["diagnose", "--data", "{rec}", "--report", "{file}"], ["--report", "folder"]),
    ("diagnose_report_is_data", ["diagnose", "--data", "{rec}", "--report", "{rec}"], ["--report", "--data"]),
    ("diagnose_candidates", ["diagnose", "--data", "{rec}", "--candidates", "a,,b"], ["--candidates"]),
    ("sweep_spec_missing", ["sweep", "{dir}/none.toml"], ["none.toml", "no such"]),
    # an output below a plain file: refused before the work, naming the option, the output and the file in the way
    # (was a FileExistsError traceback after the simulation)
    ("simulate_csv_below_file", ["simulate", "--csv", "{file}/x.csv"], ["--csv", "plain.txt/x.csv", "is a file"]),
    ("simulate_plot_below_file", ["simulate", "--plot", "{file}/s.png"], ["--plot", "plain.txt/s.png", "is a file"]),
    ("design_plot_below_file", ["design", "--plot", "{file}/d.png"], ["--plot", "plain.txt/d.png", "is a file"]),
    ("verify_report_below_file", ["verify", "--report", "{file}/sub"], ["--report", "plain.txt", "is a file"]),
    ("optimize_report_file", ["optimize-ramp", "--report", "{file}"], ["--report", "plain.txt", "is a file"]),
    ("sweep_spec_dir", ["sweep", "{dir}"], ["folder"]),
]

# --- sweep specs (run with --dry-run) ---------------------------------------------------------------
P = '[parameters.m_v]\nvalues = [3e5, 6e5]\n'
SPECS = [
    ("unknown_top", 'modle = "micro"\n' + P, ["modle", "model"]),
    ("method", 'method = "sobol"\n' + P, ["sobol"]),
    ("grid_with_n", 'n = 5\n' + P, ["n is for"]),
    ("lhs_without_n", 'method = "lhs"\n[parameters.m_v]\nmin = 3e5\nmax = 6e5\n', ["needs n"]),
    ("no_parameters", 'model = "micro"\n', ["[parameters]"]),
    ("parameters_not_table", 'parameters = 5\n', ["[parameters]"]),
    ("variable_not_table", '[parameters]\nm_v = 5\n', ["[parameters.m_v]"]),
    ("values_empty", '[parameters.m_v]\nvalues = []\n', ["values is empty"]),
    ("values_not_list", '[parameters.m_v]\nvalues = 5\n', ["values must be a list"]),
    ("values_and_range", '[parameters.m_v]\nvalues = [1]\nmin = 1\n', ["either values"]),
    ("grid_missing_num", '[parameters.m_v]\nmin = 3e5\nmax = 6e5\n', ["num"]),
    ("min_above_max", '[parameters.m_v]\nmin = 6e5\nmax = 3e5\nnum = 3\n', ["[parameters.m_v]", "low"]),
    ("num_zero", '[parameters.m_v]\nmin = 3e5\nmax = 6e5\nnum = 0\n', ["num"]),
    ("num_text", '[parameters.m_v]\nmin = 3e5\nmax = 6e5\nnum = "5"\n', ["num"]),
    ("num_float", '[parameters.m_v]\nmin = 3e5\nmax = 6e5\nnum = 2.5\n', ["num"]),
    ("num_huge", '[parameters.m_v]\nmin = 3e5\nmax = 6e5\nnum = 10000000\n', ["num", "--max-points"]),
    ("grid_product_huge", '[parameters.m_v]\nmin = 3e5\nmax = 6e5\nnum = 1000\n'
                          '[parameters.mu_c]\nmin = 0.3\nmax = 0.4\nnum = 1000\n', ["--max-points"]),
    ("n_huge", 'method = "montecarlo"\nn = 1000000000\n[parameters.m_v]\nmin = 3e5\nmax = 6e5\n', ["--max-points"]),
    ("scale", '[parameters.m_v]\nmin = 3e5\nmax = 6e5\nnum = 3\nscale = "ln"\n', ["scale"]),
    ("log_negative", '[parameters.mu_c]\nmin = -1\nmax = 0.4\nnum = 3\nscale = "log"\n', ["log"]),
    ("dist_unknown", 'method = "lhs"\nn = 4\n[parameters.m_v]\ndist = "gauss"\nmean = 1\nstd = 1\n', ["gauss"]),
    ("dist_missing", 'method = "lhs"\nn = 4\n[parameters.m_v]\ndist = "normal"\nmean = 5e5\n', ["std"]),
    ("dist_in_grid", '[parameters.m_v]\ndist = "normal"\nmean = 5e5\nstd = 1e4\n', ["dist"]),
    ("std_zero", 'method = "lhs"\nn = 4\n[parameters.m_v]\ndist = "normal"\nmean = 5e5\nstd = 0\n', ["std"]),
    ("unknown_variable", '[parameters.m_vv]\nvalues = [1.0]\n', ["m_vv", "m_v"]),
    ("impossible_points", '[parameters.mu_c]\nvalues = [0.3, 0.9]\n', ["mu_c", "points"]),
    ("unknown_output", 'outputs = ["peak_stres_Pa"]\n' + P, ["peak_stres_Pa"]),
    ("outputs_number", 'outputs = 5\n' + P, ["outputs"]),
    ("t_end_negative", 't_end = -1.0\n' + P, ["t_end"]),
    ("t_end_text", 't_end = "long"\n' + P, ["t_end"]),
    ("t_end_huge", 't_end = 1e7\n' + P, ["t_end", "max_samples"]),
    ("config_missing", 'config = "none.toml"\n' + P, ["none.toml"]),
    ("config_number", 'config = 5\n' + P, ["config"]),
    ("base_unknown", '[base]\nm_vv = 1\n' + P, ["m_vv"]),
    ("base_bad_value", '[base]\nR_a = -1\n' + P, ["R_a"]),
    ("base_not_table", 'base = 5\n' + P, ["[base]"]),
    ("options_unknown", '[options]\nrtoll = 1e-6\n' + P, ["rtoll", "rtol"]),
    ("options_dt_text", '[options]\ndt = "fine"\n' + P, ["dt"]),
    ("options_not_table", 'options = 5\n' + P, ["[options]"]),
    ("effects_unknown", 'effects = ["second_motr"]\n' + P, ["second_motr"]),
    ("effects_string", 'effects = "second_motor"\n' + P, ["effects"]),
    ("remove_absent", 'model = "macro"\nremove = ["mesh"]\n' + P, ["mesh"]),
    ("redesign_text", 'redesign = "yes"\n' + P, ["redesign"]),
    ("factor_not_list", '[parameters.f]\nfactor = "mu_c"\nvalues = [1.0]\n', ["factor"]),
    ("factor_unknown", '[parameters.f]\nfactor = ["mu_cc"]\nvalues = [1.0]\n', ["mu_cc"]),
    ("seed_negative", 'method = "lhs"\nn = 3\nseed = -1\n[parameters.m_v]\nmin = 3e5\nmax = 6e5\n', ["seed"]),
    ("model_unknown", 'model = "mezzo"\n' + P, ["mezzo"]),
    ("name_table", '[name]\nx = 1\n' + P, ["name"]),
    ("spec_bom", b"\xef\xbb\xbf" + P.encode(), ["byte-order mark"]),
]

# --- measurement records (compare --data) ------------------------------------------------------------
RECORDS = [
    ("empty", "", ["rec.csv"]),
    ("header_only", RECORD_HEAD, ["rec.csv"]),
    ("no_time_column", "t,current_A,speed_rpm\n0,1,2\n0.1,1,2\n", ["rec.csv", "time"]),
    ("text_value", RECORD_HEAD + "0.0,1,2\n0.02,abc,3\n", ["rec.csv", "abc"]),
    ("nan_value", RECORD_HEAD + "0.0,1,2\n0.02,nan,3\n0.04,1,2\n", ["rec.csv"]),
    ("time_backwards", RECORD_HEAD + "0.0,1,2\n0.02,1,2\n0.01,1,2\n", ["rec.csv", "time"]),
    ("short_row", RECORD_HEAD + "0.0,1,2\n0.02,1\n", ["rec.csv"]),
    ("binary", b"\x00\x01\x02\xff\xfe", ["rec.csv"]),
]


def _run(argv, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse refuses before kilnctl runs
        code = exc.code
    except BaseException:  # anything else is the bug this test looks for
        pytest.fail("traceback:\n" + traceback.format_exc())
    out = capsys.readouterr()
    return code, out.err


def _check(code, err, names):
    assert code == 2, err
    assert "Traceback" not in err
    for name in names:
        assert name in err, f"{name!r} not in: {err}"


@pytest.fixture
def files(tmp_path):
    (tmp_path / "folder").mkdir()
    (tmp_path / "plain.txt").write_text("not a folder")
    (tmp_path / "good.toml").write_text("[kiln]\nm_v = 6e5\n")
    (tmp_path / "good.csv").write_text(GOOD_RECORD)
    return {"dir": str(tmp_path / "folder"), "file": str(tmp_path / "plain.txt"), "cfg": str(tmp_path / "good.toml"),
            "rec": str(tmp_path / "good.csv"), "root": tmp_path}


def _write(path, content):
    (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    return str(path)


@pytest.mark.parametrize("case, content, names", CONFIGS, ids=[c[0] for c in CONFIGS])
def test_bad_config_file(case, content, names, files, capsys):
    cfg = _write(files["root"] / "cfg.toml", content)
    _check(*_run(["params", "--config", cfg], capsys), names)


@pytest.mark.parametrize("case, content, names", STRICT, ids=[c[0] for c in STRICT])
def test_implausible_values_warn_and_strict_refuses(case, content, names, files, capsys):
    cfg = _write(files["root"] / "cfg.toml", content)
    code, err = _run(["params", "--config", cfg, "--json"], capsys)
    assert code == 0 and "warning" in err and all(n in err for n in names)
    lines = err.strip().splitlines()
    assert all("warning" in ln for ln in lines) and len(set(lines)) == len(lines)  # each printed once
    _check(*_run(["params", "--config", cfg, "--strict"], capsys), names + ["--strict"])


@pytest.mark.parametrize("case, argv, names", OPTIONS, ids=[c[0] for c in OPTIONS])
def test_bad_option(case, argv, names, files, capsys):
    argv = [a.format(**files) for a in argv]
    _check(*_run(argv, capsys), names)


@pytest.mark.parametrize("case, content, names", SPECS, ids=[c[0] for c in SPECS])
def test_bad_sweep_spec(case, content, names, files, capsys):
    spec = _write(files["root"] / "spec.toml", content)
    _check(*_run(["sweep", spec, "--dry-run"], capsys), names + ["spec.toml"])


@pytest.mark.parametrize("case, content, names", RECORDS, ids=[c[0] for c in RECORDS])
def test_bad_record(case, content, names, files, capsys):
    rec = _write(files["root"] / "rec.csv", content)
    _check(*_run(["compare", "--data", rec], capsys), names)


def test_the_table_has_at_least_80_cases():
    assert len(CONFIGS) + len(STRICT) + len(OPTIONS) + len(SPECS) + len(RECORDS) >= 80


def test_loosening_zeta_never_makes_the_design_infeasible():
    # independent truth: the definition of a looser requirement -- a design meeting zeta_min = z also meets
    # any lower floor, so a lower floor must find a design wherever a higher one does (issue 11: --zeta 0
    # failed while --zeta 0.3 succeeded)
    from kilnctl.design import Requirements, design_pid
    from kilnctl.params import Parameters

    p = Parameters()
    feasible = {}
    for z in (0.0, 0.05, 0.15, 0.3, 0.5, 0.7, 0.9):
        r = design_pid(p, Requirements(zeta_min=z), strict=False)
        feasible[z] = not r.unmet
        if feasible[z]:  # checked on the closed-loop poles of both conditions
            assert min(rep.zeta_min_all for rep in r.reports.values()) >= z - 1e-9
    zs = sorted(feasible)
    for i, z in enumerate(zs):
        if feasible[z]:
            assert all(feasible[lo] for lo in zs[:i]), feasible
    assert feasible[0.0]


def test_parameters_api_refuses_the_same_values():
    # the library refuses what the CLI refuses (the CLI only adds the file name)
    from kilnctl.params import Parameters

    for kw in ({"R_a": 1e300}, {"m_v": 1e300}, {"delta_x": 8.0}):
        with pytest.raises(ParameterError, match=next(iter(kw))):
            Parameters(**kw)


def test_an_output_that_cannot_be_written_is_an_error_naming_it(tmp_path):
    # truth: a plain file made by hand stands where the output's folder would be; nothing may be left behind
    from kilnctl.errors import ConfigFileError
    from kilnctl.files import write_atomic

    (tmp_path / "plain.txt").write_text("keep")
    with pytest.raises(ConfigFileError, match=r"plain\.txt/out\.csv: cannot write it"):
        write_atomic(tmp_path / "plain.txt" / "out.csv", "a,b\n")
    assert (tmp_path / "plain.txt").read_text() == "keep" and sorted(p.name for p in tmp_path.iterdir()) == ["plain.txt"]


def test_an_unknown_effect_lists_each_valid_name_once(files, capsys):
    # truth: the name typed by hand, one letter short of the catalogue's 'second_motor'; the hint listed it
    # twice ("did you mean 'second_motor' or 'second_motor' or 'dc_motor'?"): an effect is also a component
    code, err = _run(["compare", "--data", files["rec"], "--effects", "second_motr"], capsys)
    _check(code, err, ["second_motr", "second_motor"])
    assert err.count("'second_motor'") == 1, err
    code, err = _run(["design", "--effects", "foo"], capsys)
    _check(code, err, ["'foo'", "valid names are"])
    names = err.split("valid names are: ")[1].strip().split(", ")
    assert len(names) == len(set(names)), err
