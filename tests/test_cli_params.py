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
