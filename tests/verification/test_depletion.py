"""Depletion verification: poroelastic loading against closed forms.

1. Uniaxial strain (``closed_form_depletion.uniaxial_strain_change``): a box
   with rollers on its sides, u_y = 0 at the bottom and a constant overburden
   on the top (loading.stress = initial_stress).  The FE solution is exact for
   this state (uniform strain per layer on a mesh aligned with the layers), so
   the bulk stresses are asserted to round-off (1e-10 relative), homogeneous
   and layered (reservoir layer spanning the width, host with other E, nu).
2. A fluid-filled stuck fracture in a uniformly depleting body (alpha = 1)
   does not perturb it: the Biot body load and the fracture fluid load cancel
   on the fracture (xfemslip.fem.poro, eqs. 1-2), so the stress stays the closed
   form to round-off and the jump stays the penalty's elastic part.
3. Critical depletion of a fracture inside a reservoir layer (bisection of
   ``xfemslip.studies.depletion``) against Coulomb on the rotated effective stress of
   the uniaxial path (``critical_change_uniaxial``).  Measured (fracture of
   length L = 30 m at 60 degrees, f = 0.5): relative error 1.28e-3 at h = 5 m
   (L/6 cells), 1.23e-4 at h = 2.5 m; the same 1.28e-3 with kn = kt = 1e14
   and 1e15 Pa/m instead of the automatic 4e12 (so it is the mesh, not the
   penalty).  Asserted: bisection tolerance + 2e-3 relative at h = 5 m, and
   the linear-response cross-check within the tolerance of the bisection.
4. Jansen & Meulenbroek (2022): vertical fault through an offset reservoir
   (``closed_form_depletion``, eqs. J1 and J2), the fault ON the pressure
   boundary, mid-cell, and its fluid pressure (the mean of the two faces).
   See the tests' docstrings for the measured errors.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.depletion_cases import offset_fault_case
from xfemslip.case import build, loads_case
from xfemslip.post.fields import step_fields
from xfemslip.reference.closed_form_depletion import (
    critical_change_uniaxial,
    offset_fault_slip,
    rectangles_shear,
    uniaxial_strain_change,
)
from xfemslip.simulation import build_model, newton_solver
from xfemslip.studies.depletion import critical_depletion

pytestmark = pytest.mark.verification

S0 = (-40.0e6, -60.0e6, 0.0)


def _layer_case(*, reservoir=True, fracture=None, dp=-10.0e6, biot=0.8, steps=2):
    stress = {"xx": S0[0], "yy": S0[1]}
    return build.case_text(
        {
            "mesh": {
                "x": [0.0, 0.3, 0.5, 0.65, 1.0],
                "y": [0.0, 0.2, 0.5, 0.6, 0.7, 1.2],
            },
            "material": {"E": 20.0e9, "nu": 0.2},
            "reservoir": (
                {"box": [0.0, 0.5, 1.0, 0.7], "E": 5.0e9, "nu": 0.3}
                if reservoir
                else None
            ),
            "pore_pressure": {
                "initial": 30.0e6,
                "change": dp,
                "biot": biot,
                "region": "reservoir" if reservoir else "all",
            },
            "fractures": None if fracture is None else [fracture],
            "loading": {"initial_stress": stress, "stress": stress, "steps": steps},
            "boundary": {
                "left": {"ux": 0.0},
                "right": {"ux": 0.0},
                "bottom": {"uy": 0.0},
                "top": "traction",
            },
        }
    )


def _final_fields(text):
    model = build_model(loads_case(text, "depletion.toml"))
    solver = newton_solver(model)
    solver.run(model.spec.loading.steps)
    return model, step_fields(model, solver.completed[-1])


def _expected(nu, biot, dp, p0=30.0e6):
    """(total xx, yy, zz, effective xx, yy) after dp, tension positive."""
    ch = uniaxial_strain_change(dp, nu, biot)
    sxx, syy = S0[0] + ch["xx"], S0[1]
    exx = S0[0] + biot * p0 + ch["xx_eff"]
    eyy = S0[1] + biot * p0 + ch["yy_eff"]
    # plane strain: sigma'_zz = nu (sigma'_xx + sigma'_yy), sigma_zz = sigma'_zz - a p
    szz = nu * (exx + eyy) - biot * (p0 + dp)
    return np.array([sxx, syy, szz, exx, eyy])


def _actual(f, cells):
    return np.column_stack(
        [
            f.stress[cells, 0],
            f.stress[cells, 1],
            f.stress_zz[cells],
            f.effective_stress[cells, 0],
            f.effective_stress[cells, 1],
        ]
    )


def test_uniaxial_strain_homogeneous_exact():
    model, f = _final_fields(_layer_case(reservoir=False))
    want = _expected(0.2, 0.8, -10.0e6)
    got = _actual(f, np.arange(model.mesh.n_cells))
    np.testing.assert_allclose(got, np.broadcast_to(want, got.shape), rtol=1e-10)
    np.testing.assert_allclose(f.stress[:, 2], 0.0, atol=1e-10 * abs(S0[1]))
    # the signs of the brief: total horizontal less compressive, effective
    # vertical more compressive by alpha |dp|, effective horizontal by
    # nu / (1 - nu) of that
    assert want[0] - S0[0] == pytest.approx(0.8 * 0.6 / 0.8 * 10.0e6)
    assert want[4] - (S0[1] + 0.8 * 30.0e6) == pytest.approx(-0.8 * 10.0e6)
    d_exx = want[3] - (S0[0] + 0.8 * 30.0e6)
    assert d_exx == pytest.approx(0.2 / 0.8 * (-0.8 * 10.0e6))


def test_uniaxial_strain_layered_exact():
    """Reservoir layer 0.5 < y < 0.7 (E = 5 GPa, nu = 0.3) in host rock
    (E = 20 GPa, nu = 0.2); dp acts in the layer only: the closed form holds
    in the layer with its nu, and the host keeps its in-situ stress."""
    model, f = _final_fields(_layer_case(reservoir=True))
    inside = model.materials.cell == 1
    assert inside.sum() == 8  # the two rows of cells of the layer
    got = _actual(f, np.nonzero(inside)[0])
    want = _expected(0.3, 0.8, -10.0e6)
    np.testing.assert_allclose(got, np.broadcast_to(want, got.shape), rtol=1e-10)
    host = _actual(f, np.nonzero(~inside)[0])
    want_host = _expected(0.2, 0.8, 0.0)
    np.testing.assert_allclose(host, np.broadcast_to(want_host, host.shape), rtol=1e-10)
    np.testing.assert_allclose(f.pore_pressure[inside], 20.0e6, rtol=1e-15)
    np.testing.assert_allclose(f.pore_pressure[~inside], 30.0e6, rtol=1e-15)


STUCK_FRACTURE = {
    "points": [[0.13, 0.0], [0.82, 1.2]],
    "friction": 0.6,
    "cohesion": 1.0e9,
}


def _fluid_fracture_run(kn):
    fracture = dict(STUCK_FRACTURE, kn=kn, kt=kn)
    model, f = _final_fields(_layer_case(reservoir=False, fracture=fracture, biot=1.0))
    want = _expected(0.2, 1.0, -10.0e6)
    got = _actual(f, np.arange(model.mesh.n_cells))
    return np.max(np.abs(got - want)) / 10.0e6, f, want


def test_fluid_filled_fracture_does_not_perturb():
    """alpha = 1, uniform dp: the fluid load of the stuck fracture (eq. 2)
    cancels the Biot body load on it (eq. 1), so the only departure from the
    uniform closed-form state is the penalty compliance of the faces, which
    carry the change of effective traction: measured max stress error / |dp|
    1.08e-4, 1.08e-5, 1.08e-6, 1.08e-7 at kn = kt = 1e14 .. 1e17 Pa/m,
    exactly 1/kn.  (With eq. 2 of the wrong sign, or missing, the error is
    O(1) whatever kn.)  The fracture reports p_f = p0 + dp and
    sigma_n' = sigma_n + p_f."""
    err15, _, _ = _fluid_fracture_run(1.0e15)
    err16, f, want = _fluid_fracture_run(1.0e16)
    assert err16 < 2.0e-6
    assert 9.0 < err15 / err16 < 11.0  # the penalty's 1/kn, nothing else
    fr = f.fractures[0]
    np.testing.assert_allclose(fr.fluid_pressure, 20.0e6, rtol=1e-15)
    th = np.arctan2(1.2, 0.69)
    n = np.array([-np.sin(th), np.cos(th)])
    t = np.array([np.cos(th), np.sin(th)])
    sig = np.array([[want[0], 0.0], [0.0, want[1]]])
    scale = 1.0e-5 * abs(want[1])
    np.testing.assert_allclose(fr.normal_traction, n @ sig @ n, atol=scale)
    np.testing.assert_allclose(
        fr.effective_normal_traction, n @ sig @ n + 20.0e6, atol=scale
    )
    np.testing.assert_allclose(fr.shear_traction, t @ sig @ n, atol=scale)
    assert np.all(fr.state == 1)


CRIT_CASE = build.case_text(
    {
        "domain": {"size": [200.0, 120.0]},
        "mesh": {"elements": [40, 24]},
        "material": {"E": 20.0e9, "nu": 0.25},
        "reservoir": {"box": [0.0, 40.0, 200.0, 80.0], "E": 8.0e9, "nu": 0.2},
        "pore_pressure": {
            "initial": 30.0e6,
            "change": -20.0e6,
            "region": "reservoir",
        },
        "fractures": [
            {"center": [101.0, 60.0], "length": 30.0, "angle": 60.0, "friction": 0.5}
        ],
        "loading": {
            "initial_stress": {"xx": -44.0e6, "yy": -62.0e6},
            "stress": {"xx": -44.0e6, "yy": -62.0e6},
            "steps": 4,
        },
        "boundary": {
            "left": {"ux": 0.0},
            "right": {"ux": 0.0},
            "bottom": {"uy": 0.0},
            "top": "traction",
        },
    }
)


def test_critical_depletion_against_stress_path():
    """Bisection of the first slip vs Coulomb on the uniaxial stress path."""
    model = build_model(loads_case(CRIT_CASE, "crit.toml"))
    tol = 1.0e3  # Pa
    onsets, results = critical_depletion(newton_solver(model), model, 4, tol)
    ref = critical_change_uniaxial((-44.0e6, -62.0e6, 0.0), 30.0e6, 0.2, 60.0, 0.5)
    assert ref == pytest.approx(-13.7325e6, rel=1e-4)  # hand value (docs/depletion.md)
    o = onsets[0]
    assert o.dp_lower > o.dp_upper  # bracket: stuck above, slipping below
    assert abs(o.dp_upper - o.dp_lower) <= tol
    assert abs(o.dp_critical - ref) <= tol + 2.0e-3 * abs(ref)
    # linear (all-stuck) extrapolation: an independent route to the same onset
    assert abs(o.dp_linear - o.dp_critical) <= tol
    # the step after the onset slips, the ones before do not
    slipping = [bool(np.any(r.contact.state == 2)) for r in results]
    assert slipping == [lam * -20.0e6 <= ref for lam in (0.25, 0.5, 0.75, 1.0)]


def _fault_run(h, **kw):
    text, corners, xf = offset_fault_case(h=h, **kw)
    model = build_model(loads_case(text, "fault.toml"))
    solver = newton_solver(model)
    solver.run(1)
    return model, solver.completed[-1].contact, corners, xf


def _stuck_fault_errors(h, **kw):
    """(rms, max) error of the patch shear tractions relative to the patch
    averages of (J1) (its rectangle form, corners at the mesh line x = 0),
    over patches more than 4 h from the four corners."""
    model, res, (a, b, c, d), _ = _fault_run(h, friction=0.6, cohesion=1.0e9, **kw)
    ip, cs = model.ip, model.contact
    far = float(model.mesh.x[-1])
    rects = [[-far, a, 0.0, b], [0.0, c, far, d]]
    # p_T = t . sigma . n with t = (0, 1), n = (-1, 0): -sigma_xy
    ref = -rectangles_shear(ip.xy[:, 0], ip.xy[:, 1], rects, -10.0e6, 0.25)
    W = np.bincount(cs.patch, weights=ip.weight)
    ref_patch = np.bincount(cs.patch, weights=ip.weight * ref) / W
    yc = np.bincount(cs.patch, weights=ip.weight * ip.xy[:, 1]) / W
    dist = np.min(np.abs(yc[:, None] - np.array([a, b, c, d])), axis=1) - W / 2
    keep = dist > 4.0 * h * (1.0 + 1e-9)  # patches ending 4 h away: out
    assert np.all(res.state == 1)
    err = res.pt[keep] - ref_patch[keep]
    rms = np.sqrt(np.mean(err**2) / np.mean(ref_patch[keep] ** 2))
    return rms, np.max(np.abs(err)) / np.max(np.abs(ref_patch[keep]))


def test_offset_fault_stuck_shear_traction():
    """Stuck fault (cohesion 1 GPa): shear traction against (J1).

    Reservoir 100 m thick, throw 30 m, E = 10 GPa, nu = 0.25, dp = -10 MPa,
    rollers at +-3 km (graded mesh, uniform h near the fault).  The fault is
    ON the pressure boundary x = 0, mid-cell (the cut cells are split per
    quadrature point, xfemslip.fem.poro), so the four reservoir corners, where
    (J1) has log singularities, lie on the fault itself, and the contact
    patches end there (xfemslip.fem.zones.loading_breaks).  Measured (rms /
    max relative error over patches > 4 h from the corners): h = 10 m
    7.4 % / 11 % (the 30 m between two corners is three cells); h = 5 m
    2.7 % / 2.8 %; h = 2.5 m 0.91 % / 1.3 % (rms order 1.4, 1.6).
    """
    rms10, max10 = _stuck_fault_errors(10.0)
    rms5, max5 = _stuck_fault_errors(5.0)
    assert rms10 < 0.08 and max10 < 0.12
    assert rms5 < 0.03 and max5 < 0.031
    assert rms5 < 0.4 * rms10  # converging


@pytest.mark.slow
def test_offset_fault_stuck_shear_traction_fine():
    """The stuck fault of the test above at h = 2.5 m (rms 0.91 %, max 1.3 %)."""
    rms, mx = _stuck_fault_errors(2.5)
    assert rms < 0.01 and mx < 0.015


def test_offset_fault_fluid_pressure_is_the_mean_of_the_faces():
    """Fault on the pressure boundary: p_f = p0 + dp (c_left + c_right) / 2
    (poro eq. 3), c_left = 1 for a < y < b (left reservoir), c_right = 1 for
    c < y < d: dp in the throw's overlap c < y < b, dp / 2 where one side
    depletes, 0 outside; and the cut cells report the area-mean pressure."""
    text, (a, b, c, d), _ = offset_fault_case(h=10.0)
    model = build_model(loads_case(text, "fault.toml"))
    y = model.ip.xy[:, 1]
    assert np.all(model.ip.xy[:, 0] == 0.0)
    left = (y > a) & (y < b)
    right = (y > c) & (y < d)
    want = 10.0e6 - 10.0e6 * (left.astype(float) + right) / 2.0
    got = model.pore.fluid(1.0)
    np.testing.assert_allclose(got, want, rtol=1e-15)
    assert {0.0, 0.5, 1.0} == set(np.unique(model.pore.point_ratio))
    cb = model.mesh.bounds
    yc = 0.5 * (cb[:, 2] + cb[:, 3])
    cut = (cb[:, 0] < 0.0) & (cb[:, 1] > 0.0)
    frac = ((yc > a) & (yc < b)).astype(float) / 2 + ((yc > c) & (yc < d)) / 2
    np.testing.assert_allclose(model.pore.cell_fraction[cut], frac[cut], rtol=1e-12)


def _slip_errors(h, **kw):
    model, res, (a, b, c, d), _ = _fault_run(h, **kw)
    f = step_fields(model, _Result(res)).fractures[0]
    mu = 10.0e9 / (2.0 * 1.25)
    ref = offset_fault_slip(f.points[:, 1], a, b, c, d, -10.0e6, 0.25, mu)
    assert np.all(f.state == 2) and np.all(f.effective_normal_traction < 0.0)
    err = f.slip - ref
    return np.sqrt(np.mean(err**2) / np.mean(ref**2)), f.slip, ref


class _Result:
    """The parts of a StepResult that step_fields reads."""

    def __init__(self, res):
        self.contact = res
        self.u = res.u
        self.step = 1
        self.load_factor = 1.0
        self.iterations = 0


def test_offset_fault_frictionless_slip():
    """Frictionless fault: slip against (J2), piecewise linear.

    The fault runs ON the pressure boundary x = 0, mid-cell (per-QP pressure
    in the cut cells).  Measured relative L2 slip errors: h = 10 m 1.61 %,
    h = 5 m 0.67 %, h = 2.5 m 0.41 %, h = 1.25 m 0.38 % (order 1.3, then
    levelling off: with rollers at +-6 km instead of +-3 km the h = 2.5 /
    1.25 m errors are 0.29 / 0.23 %, so the domain truncation is now a part
    of it).  The former set-up, fault half a cell off the boundary, gave
    12.8 / 6.6 / 3.4 % (the geometric offset).  The plateau (0.0375 m in the
    throw's overlap) is reached to 0.2 % at h = 5 m.
    """
    e10, _, _ = _slip_errors(10.0)
    e5, slip, ref = _slip_errors(5.0)
    assert e10 < 0.019 and e5 < 0.008
    assert e5 < 0.5 * e10
    # the sign: the side whose reservoir lies lower (left) moves down
    assert np.min(slip) < 0.0
    assert np.min(slip) == pytest.approx(np.min(ref), rel=0.005)


@pytest.mark.slow
def test_offset_fault_frictionless_slip_fine():
    """The frictionless fault of the test above at h = 2.5 m (0.41 %)."""
    e, _, _ = _slip_errors(2.5)
    assert e < 0.005
