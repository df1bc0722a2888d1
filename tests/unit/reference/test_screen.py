"""Closed-form screening (xfemslip.reference.screen) against hand-computed numbers and
against xfemslip.reference.closed_form; the ``xfemslip screen`` command.

Hand numbers, stress (xx, yy, xy) = (-20, -40, 0) MPa, plane at 45 degrees:
n = (-1, 1)/sqrt 2, t = (1, 1)/sqrt 2, so sigma_n = (-20 - 40)/2 = -30 MPa and
tau = t.sigma.n = (20 - 40)/2 = -10 MPa.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from xfemslip.cli import cli
from xfemslip.reference.closed_form import crack_tractions, slip_window
from xfemslip.reference.screen import (
    coulomb_margin,
    effective_stress,
    orientation_table,
    plane_stresses,
    pressure_to_slip,
    screen_fracture,
    slip_band,
    slip_tendency,
)

MPA = 1e6
ROOT = Path(__file__).resolve().parents[3]
PAPER = (-20 * MPA, -40 * MPA, 0.0)


def test_hand_numbers_at_45_degrees():
    sn, tau = plane_stresses(PAPER, 45.0)
    assert sn == pytest.approx(-30 * MPA, rel=1e-14)
    assert tau == pytest.approx(-10 * MPA, rel=1e-14)
    assert slip_tendency(sn, tau) == pytest.approx(1 / 3)
    # f = 0.1: 0.1 * 30 - 10 = -7 MPa, slips in situ: dp = 0
    assert coulomb_margin(sn, tau, 0.1) == pytest.approx(-7 * MPA)
    fs = screen_fracture("f", 45.0, PAPER, 0.0, 0.1)
    assert fs.dp_critical == 0.0 and not fs.opens
    # f = 0.6: 18 - 10 = 8 MPa stable; slips once p rises by 8 / 0.6 MPa,
    # before it would open (30 MPa)
    fs = screen_fracture("f", 45.0, PAPER, 0.0, 0.6)
    assert fs.margin == pytest.approx(8 * MPA)
    assert fs.dp_critical == pytest.approx(8 / 0.6 * MPA) and not fs.opens


def test_pore_pressure_makes_the_normal_stress_less_compressive():
    # p = 10 MPa: sigma' = (-10, -30) MPa; at 45 degrees sigma_n' = -20, tau = -10
    eff = effective_stress(PAPER, 10 * MPA)
    assert eff == (-10 * MPA, -30 * MPA, 0.0)
    fs = screen_fracture("f", 45.0, PAPER, 10 * MPA, 0.6)
    assert fs.sigma_n_eff == pytest.approx(-20 * MPA)
    assert fs.slip_tendency == pytest.approx(0.5)
    assert fs.margin == pytest.approx(2 * MPA)
    assert fs.dp_critical == pytest.approx(2 / 0.6 * MPA)
    # the pressure change found is where the margin is zero
    at = screen_fracture("f", 45.0, PAPER, 10 * MPA + fs.dp_critical, 0.6)
    assert at.margin == pytest.approx(0.0, abs=1e-6)


def test_cohesion_and_opening_come_first_when_friction_is_zero():
    # f = 0, c = 12 MPa > |tau| = 10 MPa: tau does not change with p, so the
    # plane stays stuck until it opens at dp = 30 MPa
    found = pressure_to_slip(-30 * MPA, -10 * MPA, 0.0, 12 * MPA)
    assert found.change == pytest.approx(30 * MPA) and found.opens
    # f = 0, c = 5 MPa < |tau|: slipping already, whatever the pressure
    assert pressure_to_slip(-30 * MPA, -10 * MPA, 0.0, 5 * MPA).change == 0.0
    # large cohesion with friction: opening (30 MPa) before Coulomb (130 MPa)
    found = pressure_to_slip(-30 * MPA, -10 * MPA, 0.1, 20 * MPA)
    assert found.change == pytest.approx(30 * MPA) and found.opens
    # at constant total stress a drop of p only closes the plane: never, down
    # to p = 0
    found = pressure_to_slip(-30 * MPA, -10 * MPA, 0.6, 0.0, -1.0, 20 * MPA)
    assert np.isnan(found.change) and not found.opens


def test_plane_stresses_match_closed_form_crack_tractions():
    stress = (-12 * MPA, -35 * MPA, 7 * MPA)
    thetas = np.linspace(-180.0, 180.0, 73)
    sn, tau = plane_stresses(stress, thetas)
    ref = np.array([crack_tractions(stress, t) for t in thetas])
    np.testing.assert_allclose(sn, ref[:, 0], rtol=1e-12)
    np.testing.assert_allclose(tau, ref[:, 1], rtol=0, atol=1e-12 * 35 * MPA)
    # exact zeros at multiples of 90 degrees (no 6e-17 leftovers)
    assert plane_stresses(PAPER, 90.0)[1] == 0.0
    assert plane_stresses(PAPER, 0.0)[1] == 0.0


@pytest.mark.parametrize(
    ("stress", "p", "f", "c"),
    [
        (PAPER, 0.0, 0.1, 0.0),
        (PAPER, 0.0, 0.3, 0.0),
        (PAPER, 8 * MPA, 0.4, 0.5 * MPA),
        ((-30 * MPA, -18 * MPA, 6 * MPA), 2 * MPA, 0.2, 0.0),  # rotated sigma_1
    ],
)
def test_band_agrees_with_the_orientation_table(stress, p, f, c):
    """The analytic band (slip_window about sigma_1) and the sampled margins
    classify every orientation alike (1e-3 degrees away from the band edges)."""
    band = slip_band(effective_stress(stress, p), f, c)
    thetas = np.arange(0.0, 180.0, 0.25)
    table = orientation_table(stress, p, f, c, thetas)
    in_band = np.zeros(thetas.size, bool)
    near_edge = np.zeros(thetas.size, bool)
    for lo, hi in band.theta:
        in_band |= (thetas > lo) & (thetas < hi)
        near_edge |= (np.abs(thetas - lo) < 1e-3) | (np.abs(thetas - hi) < 1e-3)
    np.testing.assert_array_equal(table["slips"][~near_edge], in_band[~near_edge])
    assert table["slips"].any()


def test_band_of_the_paper_state():
    """sigma_1 = 40 MPa vertical, sigma_3 = 20 MPa, f = 0.1: beta in the window
    of closed_form.slip_window, theta = 90 -/+ beta; f = 0.6: nothing slips."""
    band = slip_band(PAPER, 0.1)
    assert band.dir1 == pytest.approx(90.0)
    lo, hi = slip_window(40 * MPA, 20 * MPA, 0.1)
    assert band.beta == pytest.approx((lo, hi))
    np.testing.assert_allclose(
        band.theta, [(90 - hi, 90 - lo), (90 + lo, 90 + hi)], rtol=1e-12
    )
    # by hand: S = 3 sin(atan 0.1) = 0.29851, beta_min = (asin S - phi)/2
    phi = math.atan(0.1)
    assert lo == pytest.approx(math.degrees((math.asin(3 * math.sin(phi)) - phi) / 2))
    assert slip_band(PAPER, 0.6).beta is None
    assert slip_band(PAPER, 0.6).theta == ()


def test_cli_screen_case(runner, tmp_path):
    case = "cases/reservoir_depletion.toml"
    out = tmp_path / "fig"
    csv_path = tmp_path / "table.csv"
    result = runner.invoke(
        cli,
        ["screen", case, "--step", "45", "--csv", str(csv_path), "--plot", str(out)],
    )
    assert result.exit_code == 0, result.stderr
    text = result.stdout
    assert "slip band: beta = 5.83..78.46 deg from sigma1" in text
    assert "fractures[0]: theta = 45.00 deg (beta = 45.00 deg)" in text
    assert "margin = -7 MPa -> SLIPS already" in text
    assert (out / "mohr.png").stat().st_size > 10_000
    assert (out / "mohr.pdf").read_bytes()[:4] == b"%PDF"
    rows = csv_path.read_text().splitlines()
    assert rows[0].startswith("theta_deg,beta_deg,sigma_n_eff_Pa,tau_Pa")
    assert len(rows) == 1 + 4  # 0, 45, 90, 135
    assert rows[2].split(",")[2:4] == ["-30000000", "-10000000"]


def test_cli_screen_options(runner):
    result = runner.invoke(
        cli,
        ["screen", "--stress", "-20e6", "-40e6", "0", "-p", "10e6"]
        + ["--friction", "0.6", "--angle", "45", "--step", "30"],
    )
    assert result.exit_code == 0, result.stderr
    assert "slip band: no orientation slips" in result.stdout
    assert "angle 45: theta = 45.00 deg" in result.stdout
    assert "margin = 2 MPa -> stable; slips at a pore-pressure change dp = " in (
        result.stdout
    )
    assert "slips at a pore-pressure change dp = 3.33333 MPa" in result.stdout
    assert result.stdout.startswith("signs: tension positive")
    assert "total stress xx = -20 MPa, yy = -40 MPa" in result.stdout


def test_cli_screen_compression_positive(runner):
    """The same screen compression positive: stresses and tractions turn
    sign, pressures and margins do not; the table turns with them."""
    args = ["screen", "--stress", "-20e6", "-40e6", "0", "-p", "10e6"]
    args += ["--friction", "0.6", "--angle", "45", "--step", "45"]
    tension = runner.invoke(cli, args).stdout
    compression = runner.invoke(cli, [*args, "--compression-positive"]).stdout
    assert compression.startswith("signs: compression positive")
    assert "total stress xx = 20 MPa, yy = 40 MPa, xy = 0 MPa" in compression
    assert "pore pressure p = 10 MPa" in compression
    # at 45 deg: sigma_n' = -30 + 10 = -20 MPa, tau = -10 MPa (by hand)
    assert "sigma_n' = -20 MPa, tau = -10 MPa" in tension
    assert "sigma_n' = 20 MPa, tau = 10 MPa" in compression
    row_t = [ln.split() for ln in tension.splitlines() if ln.split()[:1] == ["45.00"]]
    row_c = [
        ln.split() for ln in compression.splitlines() if ln.split()[:1] == ["45.00"]
    ]
    assert row_t[0][2:4] == ["-20", "-10"] and row_c[0][2:4] == ["20", "10"]


def test_cli_screen_needs_a_stress_and_a_friction(runner):
    result = runner.invoke(cli, ["screen"])
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        "Error: screen needs --stress XX YY XY or a CASE with loading.stress"
    )
    result = runner.invoke(cli, ["screen", "--stress", "-1e6", "-2e6", "0"])
    assert result.exit_code == 2
    assert "needs --friction" in result.stderr


def test_cli_screen_states_its_stress_path(runner):
    """Without a pore-pressure change the screen keeps the total stress and
    raises p, and says so, without a warning."""
    plain = runner.invoke(cli, ["screen", "cases/reservoir_depletion.toml"])
    assert plain.exit_code == 0, plain.stderr
    assert "stress path: constant total stress" in plain.stdout
    assert "pore pressure rises" in plain.stdout
    assert "WARNING" not in plain.stderr


def _dp_line(text: str, label: str) -> float:
    (line,) = [ln for ln in text.splitlines() if ln.startswith(label + ":")]
    value, unit = line.rsplit("dp = ", 1)[1].split()[:2]
    assert unit == "MPa"
    return float(value) * 1e6


def test_cli_screen_follows_the_depleting_reservoir_path(runner):
    """cases/depleting_reservoir.toml: a full-width reservoir layer between
    rollers, depleted: the screen follows uniaxial strain inside the layer
    and reports a depletion.  By hand (docs/depletion.md), in the layer
    sigma_xx = -44 MPa - (1 - 2 nu)/(1 - nu) dp with nu = 0.2, sigma_yy =
    -62 MPa, p = 30 MPa + dp; at 60 degrees (and 120, its mirror image)
    sigma_n' = -18.5 MPa + (1 - 0.75 * 0.75) dp and |tau| = 7.794 MPa -
    0.75 sin 60 cos 60 dp, and |tau| = -0.5 sigma_n' at dp = -13.7325 MPa.
    Fracture 2 lies in the host, whose stress does not change."""
    case = "cases/depleting_reservoir.toml"
    result = runner.invoke(cli, ["screen", case, "--step", "90"])
    assert result.exit_code == 0, result.stderr
    text = result.stdout
    assert "WARNING" not in result.stderr
    assert "stress path: uniaxial strain of a laterally confined layer" in text
    assert "200 m < y < 300 m" in text and "depletion (dp < 0)" in text
    assert "pore pressure p = 30 MPa" in text
    k = (1 - 2 * 0.2) / (1 - 0.2)
    s, c = math.sin(math.radians(60)), math.cos(math.radians(60))
    a0, a1 = -44e6 * s * s - 62e6 * c * c + 30e6, 1.0 - k * s * s
    b0, b1 = abs((-62e6 + 44e6) * s * c), k * s * c
    hand = (b0 + 0.5 * a0) / (b1 - 0.5 * a1)  # b0 - b1 dp = -0.5 (a0 + a1 dp)
    assert hand == pytest.approx(-13.7325e6, rel=1e-5)
    for label in ("fractures[0]", "fractures[1]"):
        assert _dp_line(text, label) == pytest.approx(hand, rel=1e-5)
    (line,) = [ln for ln in text.splitlines() if ln.startswith("fractures[2]:")]
    assert line.endswith("stable; neither slips nor opens along the path")
    # -p replaces the in-situ pore pressure on the same path: with 2 MPa
    # less, sigma_n' starts 2 MPa more compressive and the onset moves
    lower = runner.invoke(cli, ["screen", case, "-p", "28e6", "--step", "90"])
    hand_lower = (b0 + 0.5 * (a0 - 2e6)) / (b1 - 0.5 * a1)
    assert _dp_line(lower.stdout, "fractures[0]") == pytest.approx(hand_lower, rel=1e-5)
    # a plane given by its angle is screened inside the layer
    angle = runner.invoke(
        cli, ["screen", case, "--angle", "60", "--friction", "0.5", "--step", "90"]
    )
    assert _dp_line(angle.stdout, "angle 60") == pytest.approx(hand, rel=1e-5)


def test_cli_screen_warns_when_the_case_path_needs_the_full_solve(runner, tmp_path):
    """A reservoir of finite width stresses its surroundings: the closed form
    cannot follow it, the screen says why and names deplete, and keeps the
    total stress in the direction of the case's change (a depletion, which
    at constant total stress only closes the planes)."""
    text = (ROOT / "cases" / "depleting_reservoir.toml").read_text()
    case = tmp_path / "finite.toml"
    case.write_text(
        text.replace(
            "box = [0.0, 200.0, 800.0, 300.0]", "box = [100.0, 200.0, 700.0, 300.0]"
        )
    )
    result = runner.invoke(cli, ["screen", str(case)])
    assert result.exit_code == 0, result.stderr
    (line,) = [ln for ln in result.stderr.splitlines() if "WARNING" in ln]
    assert "does not span the whole width" in line
    assert f"xfemslip deplete {case}" in line
    assert "constant total stress" in result.stdout
    assert "pore pressure drops" in result.stdout
    assert "slips at a pore-pressure change" not in result.stdout
