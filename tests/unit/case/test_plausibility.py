"""Plausibility warnings: valid values that look like a mistake are named,
the shipped cases get none, and nothing is refused."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from xfemslip.case import build, load_case, loads_case
from xfemslip.case.plausibility import E_RANGE, plausibility_warnings
from xfemslip.cli import cli
from xfemslip.contact.defaults import PENALTY_RATIO_LOWEST, PENALTY_RATIO_MEASURED

CASES = Path(__file__).resolve().parents[3] / "cases"
RESERVOIR = CASES / "reservoir_depletion.toml"
H = 1.0 / 50  # the reservoir case's cell size [m]
E = 5e9


def _warnings(**keys) -> list[str]:
    text = build.case_text(build.file_case(RESERVOIR, **keys))
    return plausibility_warnings(loads_case(text, "w.toml"))


@pytest.mark.parametrize("case", sorted(CASES.glob("*.toml")), ids=lambda p: p.stem)
def test_shipped_cases_have_no_warning(case):
    assert plausibility_warnings(load_case(case)) == []


@pytest.mark.parametrize(
    ("E", "warned"),
    [(5.0, True), (5e3, True), (E_RANGE[0], False), (5e9, False), (2e12, True)],
)
def test_young_modulus_outside_the_rock_range(E, warned):
    found = [w for w in _warnings(**{"material.E": E}) if w.startswith("material.E")]
    assert bool(found) == warned
    if warned:
        assert f"{E:g} Pa" in found[0]


@pytest.mark.parametrize(
    ("stress", "warned"),
    [
        ([1e6, 2e6, 0.0], True),  # tension both ways
        ([0.0, 0.0, 1e6], False),  # pure shear: principal -1e6 compresses
        ([2e6, 1e6, 1.5e6], False),  # s_min = 1.5e6 - sqrt(0.25e12 + 2.25e12) < 0
        ([2e6, 2e6, 1e6], True),  # s_min = 1e6 >= 0
        ([-20e6, -40e6, 0.0], False),
    ],
)
def test_far_field_that_compresses_nothing(stress, warned):
    table = dict(zip(("xx", "yy", "xy"), stress, strict=True))
    found = [w for w in _warnings(**{"loading.stress": table}) if "compresses" in w]
    assert bool(found) == warned


@pytest.mark.parametrize(
    "ratio",
    [PENALTY_RATIO_LOWEST / 2, 2 * PENALTY_RATIO_MEASURED],
)
def test_penalty_outside_the_measured_range(ratio):
    kn = ratio * E / H
    found = _warnings(**{"fractures.0.kn": kn})
    (line,) = [w for w in found if w.startswith("fractures[0].kn")]
    assert f"kn*h/E = {ratio:.3g}" in line
    inside = _warnings(**{"fractures.0.kn": 10 * E / H})
    assert not any(w.startswith("fractures[0].kn") for w in inside)


def test_fracture_reaching_outside_the_domain():
    found = _warnings(**{"fractures.0.length": 3.0})
    assert any("fractures[0] reaches outside the domain" in w for w in found)


def test_check_prints_the_warnings_and_succeeds(tmp_path):
    case = tmp_path / "odd.toml"
    case.write_text(build.case_text(build.file_case(RESERVOIR, **{"material.E": 5.0})))
    result = CliRunner().invoke(cli, ["check", str(case)])
    assert result.exit_code == 0, result.output
    lines = [ln for ln in result.stderr.splitlines() if ln.startswith("WARNING")]
    assert any("material.E = 5 Pa" in ln for ln in lines)
    assert all(ln.startswith(f"WARNING: {case}: ") for ln in lines)
    assert "Error" not in result.stderr
