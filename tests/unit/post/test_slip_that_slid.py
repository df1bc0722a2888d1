"""The slip that slid (``plastic_slip``) and what is derived from it.

The tangential jump of a contact point in contact is the elastic give of the
penalty plus what slid, g_T = (p_T - p_T0) / k_T + d (the return map, paper
eqs. 26-27; p_T0 the in-situ shear): the moment, the magnitude, the max slip
and the dilation count d only.  A stuck fracture has d = 0 while its jump is
not; an open point carries no shear and its whole jump slid.  The elastic
constants of a contact point are those of the material on its faces (their
mean on a fault between two rocks), and the moment integrates them point by
point.  Everything is checked against sums written here from the arrays of
result.h5.
"""

from __future__ import annotations

import math

import h5py
import meshio
import numpy as np
import pytest

import xfemslip
from xfemslip.case import load_case
from xfemslip.conventions import OPEN, SLIP, STICK
from xfemslip.post.events import event_inputs, event_sizes, fracture_metrics
from xfemslip.simulation import build_model, run_case

E_HOST, NU_HOST = 20.0e9, 0.25
E_RES, NU_RES = 8.0e9, 0.2
MU_HOST = E_HOST / (2.0 * (1.0 + NU_HOST))  # 8 GPa
MU_RES = E_RES / (2.0 * (1.0 + NU_RES))  # 3.33 GPa
# a 45-degree fracture through no mesh node (h = 0.05: y = x - 0.04)
FRACTURE = [[0.32, 0.28], [0.72, 0.68]]
LENGTH = math.dist(*FRACTURE)
SIGMA0 = (-20.0e6, -40.0e6, 0.0)  # |tau| = 10 MPa, sigma_n = -30 MPa on it


def _case(tmp_path, name, *, friction, extra="", top="{ uy = -2.0e-4 }", initial=True):
    """A 1 m square of 20 x 20 cells, rollers on the sides, the bottom held,
    the top moved down (or ``top`` = "traction"), the fracture FRACTURE;
    ``extra`` adds tables."""
    sxx, syy, _ = SIGMA0
    stress = f"{{ xx = {sxx!r}, yy = {syy!r} }}"
    text = f"""name = "{name}"
[domain]
size = [1.0, 1.0]
[mesh]
elements = [20, 20]
[material]
E = {E_HOST!r}
nu = {NU_HOST!r}
[loading]
stress = {stress}
{"initial_stress = " + stress if initial else ""}
steps = 2
[boundary]
bottom = {{ uy = 0.0 }}
top = {top}
left = {{ ux = 0.0 }}
right = {{ ux = 0.0 }}
[output]
formats = ["h5", "vtu"]
[[fractures]]
points = {FRACTURE}
friction = {friction!r}
cohesion = 0.0
{extra}"""
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return load_case(path)


def _stretches(s, lo=0.0, hi=LENGTH):
    """Length each contact point stands for: midpoints to its neighbours,
    the ends at the fracture's ends."""
    mid = 0.5 * (s[1:] + s[:-1])
    return np.diff(np.concatenate([[lo], mid, [hi]]))


# --------------------------------------------------------------------------- #
# A fracture across two materials


@pytest.fixture(scope="module")
def across(tmp_path_factory):
    """The fracture half in a soft reservoir (y < 0.5), half in the host,
    released by its in-situ shear (friction 0.1): it slips in both."""
    tmp = tmp_path_factory.mktemp("across")
    spec = _case(
        tmp,
        "across",
        friction=0.1,
        extra="[reservoir]\nbox = [0.0, 0.0, 1.0, 0.5]\n"
        f"E = {E_RES!r}\nnu = {NU_RES!r}\n",
    )
    run_case(spec, tmp / "out")
    return spec, xfemslip.read_result(tmp / "out")


def test_moment_across_two_materials_is_the_per_point_sum(across):
    """M0' = sum_i mu_i |d_i| w_i with mu_i that of the rock the point lies
    in (its y against the reservoir's top, y = 0.5), d_i the plastic slip,
    w_i its stretch: not the middle point's mu for the whole fracture."""
    _, result = across
    ff = result.fractures[0]
    below = ff.points[:, 1] < 0.5
    slipping = ff.state == SLIP
    assert np.any(slipping & below) and np.any(slipping & ~below)  # both rocks
    mu = np.where(below, MU_RES, MU_HOST)
    np.testing.assert_array_equal(result.fracture_properties[0].shear_modulus, mu)
    np.testing.assert_array_equal(
        result.fracture_properties[0].poisson_ratio, np.where(below, NU_RES, NU_HOST)
    )
    assert result.fracture_properties[0].ends == pytest.approx((0.0, LENGTH), abs=1e-15)
    hand = float(np.sum(mu * np.abs(ff.plastic_slip) * _stretches(ff.s)))
    assert result.events.moment_per_length[-1, 0] == pytest.approx(hand, rel=1e-12)
    # the middle point lies in the host: its mu for all would be 1.6 times more
    single = MU_HOST * float(np.sum(np.abs(ff.plastic_slip) * _stretches(ff.s)))
    assert single > 1.3 * hand
    # the stress drop inverts the crack point by point: 4 / (pi a^2) int mu
    # |d| / (kappa + 1), kappa + 1 = 4 (1 - nu) in plane strain
    nu = np.where(below, NU_RES, NU_HOST)
    a = 0.5 * float(np.sum(_stretches(ff.s)[slipping]))
    crack = np.sum(mu * np.abs(ff.plastic_slip) * _stretches(ff.s) / (4 * (1 - nu)))
    drop = 4.0 * float(crack) / (math.pi * a * a)
    assert result.events.stress_drop[-1, 0] == pytest.approx(drop, rel=1e-12)


def test_a_fault_bounding_the_reservoir_gets_the_mean_of_its_faces(tmp_path):
    """A reservoir triangle whose hypotenuse is the fracture: every contact
    point has the reservoir on its - face and the host on its + face, so
    mu = (mu_res + mu_host) / 2 and likewise nu."""
    (x0, y0), (x1, y1) = FRACTURE
    polygon = [[x0, y0], [x1, y0], [x1, y1]]  # below-right of the fracture
    spec = _case(
        tmp_path,
        "bounding",
        friction=0.1,
        extra=f"[reservoir]\npolygon = {polygon}\nE = {E_RES!r}\nnu = {NU_RES!r}\n",
    )
    from xfemslip.post.fields import fracture_properties

    model = build_model(spec)
    (prop,) = fracture_properties(model)
    n = int(np.sum(model.ip.fracture == 0))
    np.testing.assert_allclose(prop.shear_modulus, np.full(n, 0.5 * (MU_RES + MU_HOST)))
    np.testing.assert_allclose(prop.poisson_ratio, np.full(n, 0.5 * (NU_RES + NU_HOST)))


# --------------------------------------------------------------------------- #
# A stuck fracture


@pytest.fixture(scope="module")
def stuck(tmp_path_factory):
    """Friction 0.8 against a shear ratio of 1/3: the fracture sticks, with a
    soft penalty (kt = 1e11 Pa/m) so that its elastic jump shows; [events]
    extent, and [permeability] with 5 degrees of dilation and no closure."""
    tmp = tmp_path_factory.mktemp("stuck")
    spec = _case(
        tmp,
        "stuck",
        friction=0.8,
        extra="kn = 1.0e11\nkt = 1.0e11\n[events]\nextent = 100.0\n"
        "[permeability]\naperture = 1.0e-4\ndilation_angle = 5.0\n",
    )
    run_case(spec, tmp / "out")
    return spec, tmp / "out"


def test_a_stuck_fracture_slid_nothing(stuck):
    """Its jump is the elastic give (p_T - p_T0) / k_T, not zero; what slid
    is zero: max slip 0, M0' 0, no magnitude even with events.extent, no
    stress drop (NaN, stored so), no dilation, and the sweep's max_Mw empty."""
    spec, out = stuck
    result = xfemslip.read_result(out)
    for step in result.steps:
        ff = step.fractures[0]
        assert np.all(ff.state == STICK)
        assert np.abs(ff.slip).max() > 1.0e-6  # 1e-5 m of elastic give
        np.testing.assert_array_equal(ff.plastic_slip, 0.0)
        # nothing slid, so the aperture is a0: no dilation from the jump
        np.testing.assert_array_equal(ff.aperture, 1.0e-4)
    events = result.events
    np.testing.assert_array_equal(events.max_slip, 0.0)
    np.testing.assert_array_equal(events.moment_per_length, 0.0)
    assert np.all(np.isnan(events.stress_drop))
    with h5py.File(out / "result.h5") as h5:
        assert np.all(np.isnan(h5["events/stress_drop"][()]))
        np.testing.assert_array_equal(h5["events/moment"][()], 0.0)
    ((event,),) = event_sizes(result, event_inputs(result))[-1:]
    assert event.magnitude == -math.inf and event.extent == 100.0
    metrics = fracture_metrics(result, spec)
    assert metrics["max_Mw"] == "" and metrics["fracture0_Mw"] == ""
    assert metrics["fracture0_max_slip_m"] == 0.0
    np.testing.assert_allclose(result.permeability.ratio(), [1.0, 1.0], rtol=1e-15)


def test_summary_of_a_stuck_fracture_prints_no_magnitude(stuck):
    from click.testing import CliRunner

    from xfemslip.cli import cli

    _, out = stuck
    printed = CliRunner().invoke(cli, ["summary", str(out)])
    assert printed.exit_code == 0, printed.output
    lines = printed.output.splitlines()
    row = lines[lines.index(next(x for x in lines if x.startswith("fracture "))) + 1]
    assert row.split() == ["0", "no", "0", "0", "0", "-", "-", "-"]
    assert "no fracture slipped (1 in all)" in printed.output


# --------------------------------------------------------------------------- #
# A sliding fracture


@pytest.fixture(scope="module")
def sliding(tmp_path_factory):
    """The fracture with one contact patch per point (contact_patch = 0) and
    kt given, friction 0.1: without initial stress, the top moved down by
    1 mm (it slips where |p_T| reaches 0.1 |p_N|)."""
    tmp = tmp_path_factory.mktemp("sliding")
    spec = _case(
        tmp,
        "sliding",
        friction=0.1,
        initial=False,
        top="{ uy = -1.0e-3 }",
        extra="kn = 1.0e12\nkt = 1.0e12\n[solver]\ncontact_patch = 0\n",
    )
    memory = run_case(spec, tmp / "out")
    return memory, tmp / "out"


def test_plastic_slip_is_the_jump_less_the_elastic_give(sliding):
    """At every slipping point d = g_T - p_T / k_T (return map, eq. 27; no
    in-situ shear here); stuck points keep what they slid before."""
    memory, _ = sliding
    for step in memory.steps:
        ff = step.fractures[0]
        slipping = ff.state == SLIP
        assert slipping.any()
        elastic = ff.shear_traction / 1.0e12
        np.testing.assert_allclose(
            ff.plastic_slip[slipping],
            (ff.slip - elastic)[slipping],
            rtol=0,
            atol=1e-12 * np.abs(ff.slip).max(),
        )
        # not the jump: the elastic give is a visible part of it
        assert np.abs(elastic[slipping]).max() > 1e-3 * np.abs(ff.slip).max()


def test_plastic_slip_in_situ_counts_from_the_in_situ_shear(across, tmp_path):
    """With initial stress the elastic give is (p_T - p_T0) / k_T, p_T0 =
    t . sigma0 . n: at slipping points d = g_T - (p_T - p_T0) / k_T."""
    spec = _case(
        tmp_path,
        "in-situ",
        friction=0.1,
        extra="kn = 1.0e12\nkt = 1.0e12\n[solver]\ncontact_patch = 0\n",
    )
    result = run_case(spec)
    ff = result.fractures[0]
    t = np.subtract(*FRACTURE[::-1]) / LENGTH
    n = np.array([-t[1], t[0]])
    sigma = np.array([[SIGMA0[0], SIGMA0[2]], [SIGMA0[2], SIGMA0[1]]])
    pt0 = float(t @ sigma @ n)  # -10 MPa
    slipping = ff.state == SLIP
    assert slipping.all()
    np.testing.assert_allclose(
        ff.plastic_slip,
        ff.slip - (ff.shear_traction - pt0) / 1.0e12,
        rtol=0,
        atol=1e-12 * np.abs(ff.slip).max(),
    )


def test_plastic_slip_and_properties_round_trip_through_the_files(sliding):
    """result.h5 holds plastic_slip at the root and at every step, and the
    fractures' shear modulus, Poisson's ratio and ends at the root;
    fractures.vtu has plastic_slip as point data, sorted by s."""
    memory, out = sliding
    read = xfemslip.read_result(out)
    for mine, back in zip(memory.steps, read.steps, strict=True):
        np.testing.assert_array_equal(
            back.fractures[0].plastic_slip, mine.fractures[0].plastic_slip
        )
    (prop,) = read.fracture_properties
    (kept,) = memory.fracture_properties
    np.testing.assert_array_equal(prop.shear_modulus, kept.shear_modulus)
    np.testing.assert_array_equal(prop.shear_modulus, MU_HOST)
    np.testing.assert_array_equal(prop.poisson_ratio, NU_HOST)
    assert prop.ends == kept.ends
    with h5py.File(out / "result.h5") as h5:
        assert h5["fractures/0/plastic_slip"].attrs["units"] == "m"
        assert h5["fractures/0/shear_modulus"].attrs["units"] == "Pa"
        for k in ("0001", "0002"):
            assert f"steps/{k}/fractures/0/plastic_slip" in h5
            assert f"steps/{k}/fractures/0/shear_modulus" not in h5
    vtu = meshio.read(out / "fractures.vtu")
    final = memory.final.fractures[0]
    np.testing.assert_array_equal(vtu.point_data["plastic_slip"], final.plastic_slip)
    np.testing.assert_array_equal(vtu.point_data["slip"], final.slip)


# --------------------------------------------------------------------------- #
# An open fracture


def test_an_open_fracture_slid_its_whole_jump(tmp_path):
    """Injection (+40 MPa on 10 MPa, the top under its traction): the
    fracture sticks at step 1 (d = 0) and opens at step 2, where it carries
    no shear and its plastic slip is its tangential jump, point for point."""
    spec = _case(
        tmp_path,
        "open",
        friction=0.6,
        top='"traction"',
        extra="[pore_pressure]\ninitial = 10.0e6\nchange = 40.0e6\n"
        "[solver]\ncontact_patch = 0\n",
    )
    result = run_case(spec)
    first, second = (step.fractures[0] for step in result.steps)
    assert np.all(first.state == STICK)
    np.testing.assert_array_equal(first.plastic_slip, 0.0)
    assert np.all(second.state == OPEN)
    assert np.abs(second.slip).max() > 1e-4  # 0.2 mm
    np.testing.assert_array_equal(second.plastic_slip, second.slip)
    np.testing.assert_array_equal(second.shear_traction, 0.0)
