"""docs/python.md runs: its Python cells, in order, in one namespace, from a
folder that has the shipped cases (their assertions check what the text
says); and a spec changed with dataclasses.replace records its own text."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from tests.support.golden import ROOT
from xfemslip.case import load_case, loads_case
from xfemslip.errors import UsageError
from xfemslip.simulation import run_case

DOC = ROOT / "docs" / "python.md"
CASE = ROOT / "cases" / "reservoir_depletion.toml"


def _cells() -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", DOC.read_text(), re.M | re.S)


def test_the_doc_runs(tmp_path, monkeypatch, capsys):
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    monkeypatch.chdir(tmp_path)
    cells = _cells()
    assert len(cells) >= 5
    namespace: dict = {}
    for cell in cells:
        exec(compile(cell, str(DOC), "exec"), namespace)  # noqa: S102
    out = capsys.readouterr().out
    assert "{'E': 5000000000.0, 'nu': 0.3, 'model': 'plane_strain'}" in out
    assert (tmp_path / "out" / "stiffer" / "result.h5").is_file()


def test_replaced_spec_records_what_ran():
    """E and a friction changed in Python: the text recorded loads back into
    the spec that ran, and the run equals the run of that text."""
    spec = load_case(CASE)
    fracture = dataclasses.replace(spec.fractures[0], friction=0.3)
    changed = dataclasses.replace(
        spec,
        material=dataclasses.replace(spec.material, E=7.0e9),
        fractures=(fracture,),
    )
    result = run_case(changed)
    text = result.attrs["case_toml"]
    assert text != spec.text
    again = loads_case(text, CASE)
    assert again.material.E == 7.0e9 and again.fractures[0].friction == 0.3
    same = run_case(again)
    assert same.run_id == result.run_id != run_case(spec).run_id
    np.testing.assert_array_equal(same.fractures[0].slip, result.fractures[0].slip)


def test_unchanged_spec_records_its_file_text():
    spec = load_case(CASE)
    assert run_case(spec).attrs["case_toml"] == CASE.read_text()


def test_change_no_text_can_say_is_refused():
    spec = load_case(CASE)
    x = spec.mesh.x.copy()
    x[1] += 0.001
    x.setflags(write=False)
    moved = dataclasses.replace(spec, mesh=dataclasses.replace(spec.mesh, x=x))
    with pytest.raises(UsageError, match=r"changed in Python in mesh"):
        run_case(moved)
