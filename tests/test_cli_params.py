"""The `kilnctl params` command, run in-process."""

import json

from kilnctl.cli import main


def test_params_json(capsys):
    assert main(["params", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["J_m"]["value"] == 21.5 and data["J_m"]["unit"] == "kg*m^2"
    assert data["J_m"]["source"] == "Table 1"


def test_params_bad_config(tmp_path, capsys):
    f = tmp_path / "c.toml"
    f.write_text("mu_c = 0.9\n")
    assert main(["params", "--config", str(f)]) == 2
    err = capsys.readouterr().err
    assert "mu_c" in err and "Traceback" not in err


def test_output_piped_into_head_ends_quietly(monkeypatch):
    # truth: a stdout that raises BrokenPipeError on write, as `kilnctl params | head -1` gives once head exits;
    # that ended in a BrokenPipeError traceback: `except Exception` in main caught it before its own clause
    import io
    import sys

    from kilnctl.cli import main

    class ClosedPipe(io.StringIO):
        def write(self, s):
            raise BrokenPipeError(32, "Broken pipe")

    err = io.StringIO()
    err.close = lambda: None  # main closes stderr so that Python's exit says nothing; keep it readable here
    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    monkeypatch.setattr(sys, "stderr", err)
    assert main(["params"]) == 0
    assert "Traceback" not in err.getvalue() and "BrokenPipe" not in err.getvalue()
