"""docs/assumptions.md is generated from the parameter declarations and must be current."""

from pathlib import Path

from kilnctl.assumptions import render
from kilnctl.params import SPECS

DOC = Path(__file__).resolve().parents[1] / "docs" / "assumptions.md"


def test_assumptions_doc_is_current():
    assert DOC.read_text() == render(), "regenerate: python -m kilnctl.assumptions > docs/assumptions.md"


def test_every_parameter_listed():
    text = DOC.read_text()
    for name in SPECS:
        assert f"| `{name}` |" in text
