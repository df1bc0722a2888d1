"""deplete on a displaced fault and in a layered reservoir: whether the
first slip sits at a singular point of the model, the pore-pressure change
at which the slipping patch reaches a given length (checked by solving to
either side of it), what result.h5 and summary keep of it."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from click.testing import CliRunner

from tests.support.golden import ROOT
from xfemslip import read_result
from xfemslip.case import build, load_case, loads_case
from xfemslip.cli import cli
from xfemslip.simulation import build_model, newton_solver
from xfemslip.studies.depletion import deplete, slipping_length

FAULT = ROOT / "cases" / "displaced_fault.toml"


def _fault(**keys):
    keys = {"mesh.size": 25.0, "output.formats": ["h5"], **keys}
    return loads_case(build.case_text(build.file_case(FAULT, **keys)), FAULT)


@pytest.fixture(scope="module")
def fault_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("fault") / "out"
    spec = _fault()
    return spec, deplete(spec, out, patch_length=60.0), out


def test_first_slip_at_a_reservoir_corner_is_said(fault_run):
    spec, report, out = fault_run
    (onset,) = report.onsets
    assert onset.at_singularity and onset.singularity == "a reservoir corner"
    # it is next to one of the four corners (y = -150, -75, 75, 150 m)
    assert np.min(np.abs(onset.y - np.array([-150.0, -75.0, 75.0, 150.0]))) < 40.0
    with open(out / "critical_depletion.csv", newline="") as fh:
        (row,) = list(csv.DictReader(fh))
    assert row["first_slip_at_singularity"] == "true"
    assert float(row["dp_patch_length_Pa"]) == pytest.approx(onset.dp_patch)
    table = read_result(out / "result.h5").depletion
    assert bool(table.at_singularity[0]) and table.patch_length == 60.0
    assert table.dp_critical[0] == pytest.approx(onset.dp_critical)
    text = CliRunner().invoke(cli, ["summary", str(out)]).output
    assert "reservoir corner where the stress is singular (mesh-dependent)" in text
    assert "slipping over 60 m from dp =" in text


def test_report_in_megapascals_either_sign_convention(fault_run):
    """The deplete table prints dp_critical in MPa (the report's own value /
    1e6 to 6 digits); compression positive prints the depletion, a drop > 0,
    and summary says which convention it uses."""
    from xfemslip.studies.depletion import format_report

    _, report, out = fault_run
    (onset,) = report.onsets
    tension = format_report(report).splitlines()
    compression = format_report(report, compression_positive=True).splitlines()
    assert tension[0].startswith("signs: tension positive")
    assert compression[0].startswith("signs: compression positive")
    row_t = next(ln.split() for ln in tension if ln.split()[:1] == ["0"])
    row_c = next(ln.split() for ln in compression if ln.split()[:1] == ["0"])
    assert float(row_t[1]) == pytest.approx(onset.dp_critical / 1e6, rel=1e-5)
    assert onset.dp_critical < 0 and float(row_c[1]) == -float(row_t[1])
    assert "dp_critical [MPa]" in tension[2] and "depletion_critical" in compression[2]
    text = CliRunner().invoke(cli, ["summary", str(out), "--compression-positive"])
    assert "signs: compression positive" in text.output
    assert f"first slip at depletion = {-onset.dp_critical / 1e6:.6g} MPa" in (
        text.output
    )


def test_patch_length_change_brackets_the_growth(fault_run):
    """Solved in one step to just below and just above dp_patch: the
    slipping length is below 60 m, then at least 60 m."""
    spec, report, _ = fault_run
    (onset,) = report.onsets
    assert abs(onset.dp_patch) >= abs(onset.dp_critical)
    change = spec.pore_pressure.change
    lengths = []
    for dp in (onset.dp_patch + report.tolerance, onset.dp_patch - report.tolerance):
        model = build_model(spec)
        solver = newton_solver(model)
        # the path the bisection followed: the steps up to its bracket, then it
        steps = spec.loading.steps
        lam = dp / change
        factors = [k / steps for k in range(1, steps + 1) if k / steps < lam]
        solver.run_path([*factors, lam])
        lengths.append(slipping_length(model.contact, solver.completed[-1].contact, 0))
    assert lengths[0] < 60.0 <= lengths[1]


def test_a_horizon_crossing_a_fracture_is_no_singularity(tmp_path):
    """In the laterally uniform reservoir layer the stress is piecewise
    uniform: neither the fracture inside it nor the one crossing its top
    slips first at a singular point (both match the closed form)."""
    report = deplete(load_case(ROOT / "cases" / "depleting_reservoir.toml"), None)
    assert [o.at_singularity for o in report.onsets] == [False, False, False]
