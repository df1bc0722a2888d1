"""xfemslip.reference.closed_form against independent facts of elasticity.

Every check below uses a property the closed form must have, not its own
formulas: Hooke's law and equilibrium by finite differences of the
displacement and stress fields, the friction law on the faces, the jump equal
to the slip profile, the remote field far away, the near-tip asymptotics
giving K_II, and the slip window's edges sitting exactly on the Coulomb line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.reference import closed_form as cf

E, NU = 5.0e9, 0.3
A = 0.5
CENTER = (0.0123, -0.0077)
STRESS = (-20.0e6, -40.0e6, 3.0e6)
PSI = 30.0
PLANES = ("plane_strain", "plane_stress")


def hooke(plane):
    """Elasticity matrix in Voigt [exx, eyy, gxy], written out independently."""
    if plane == "plane_strain":
        c = E / ((1 + NU) * (1 - 2 * NU))
        return c * np.array(
            [[1 - NU, NU, 0], [NU, 1 - NU, 0], [0, 0, (1 - 2 * NU) / 2]]
        )
    c = E / (1 - NU**2)
    return c * np.array([[1, NU, 0], [NU, 1, 0], [0, 0, (1 - NU) / 2]])


def frame(psi=PSI):
    p = math.radians(psi)
    return np.array([math.cos(p), math.sin(p)]), np.array([-math.sin(p), math.cos(p)])


def field_kw(plane, friction=0.1, cohesion=1.0e6, psi=PSI):
    return dict(
        center=CENTER,
        a=A,
        E=E,
        nu=NU,
        plane=plane,
        stress=STRESS,
        psi_deg=psi,
        friction=friction,
        cohesion=cohesion,
    )


def stress_kw(friction=0.1, cohesion=1.0e6, psi=PSI):
    return dict(
        center=CENTER,
        a=A,
        stress=STRESS,
        psi_deg=psi,
        friction=friction,
        cohesion=cohesion,
    )


def off_crack_points():
    """Points around the crack (not on it), including near its tips."""
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1.2, 1.2, size=(60, 2))
    t, n = frame()
    d = (pts - CENTER) @ n
    return pts[np.abs(d) > 0.05]


def test_the_case_slips():
    # the checks below are only meaningful with a non-zero driving shear
    assert abs(cf.driving_shear(STRESS, PSI, 0.1, 1.0e6)) > 1.0e6


@pytest.mark.parametrize("plane", PLANES)
def test_hooke_by_finite_differences_of_the_displacement(plane):
    pts = off_crack_points()
    h = 1.0e-5
    grad = np.zeros((pts.shape[0], 2, 2))
    for k, e in enumerate(np.eye(2)):
        up = cf.displacement(pts + h * e, **field_kw(plane))
        um = cf.displacement(pts - h * e, **field_kw(plane))
        grad[:, :, k] = (up - um) / (2 * h)
    eps = np.column_stack([grad[:, 0, 0], grad[:, 1, 1], grad[:, 0, 1] + grad[:, 1, 0]])
    sig = eps @ hooke(plane).T
    exact = cf.stress_field(pts, **stress_kw())
    scale = np.abs(STRESS).max()
    assert np.max(np.abs(sig - exact)) < 1.0e-5 * scale
    # and the field is not just the remote stress there
    assert np.max(np.abs(exact - [STRESS[0], STRESS[1], STRESS[2]])) > 0.05 * scale


def test_equilibrium_by_finite_differences_of_the_stress():
    pts = off_crack_points()
    h = 1.0e-5

    def d(k):
        e = np.eye(2)[k]
        return (
            cf.stress_field(pts + h * e, **stress_kw())
            - cf.stress_field(pts - h * e, **stress_kw())
        ) / (2 * h)

    dx, dy = d(0), d(1)
    div_x = dx[:, 0] + dy[:, 2]
    div_y = dx[:, 2] + dy[:, 1]
    # stress gradients are O(dtau / distance); the FD error is O(h^2)
    assert np.max(np.abs(div_x)) < 1.0e-3 * 1.0e6
    assert np.max(np.abs(div_y)) < 1.0e-3 * 1.0e6


@pytest.mark.parametrize(
    ("friction", "cohesion"), [(0.1, 0.0), (0.05, 1.0e6), (0.0, 0.0)]
)
def test_faces_carry_the_friction_bound(friction, cohesion):
    t, n = frame()
    x = np.linspace(-0.95, 0.95, 21) * A
    t_n, t_t = cf.crack_tractions(STRESS, PSI)
    assert cf.driving_shear(STRESS, PSI, friction, cohesion) != 0.0
    for side in (+1.0, -1.0):
        pts = np.asarray(CENTER) + np.outer(x, t) + side * 1.0e-9 * n
        s = cf.stress_field(pts, **stress_kw(friction, cohesion))
        sig = np.zeros((len(pts), 2, 2))
        sig[:, 0, 0], sig[:, 1, 1] = s[:, 0], s[:, 1]
        sig[:, 0, 1] = sig[:, 1, 0] = s[:, 2]
        p_n = np.einsum("i,nij,j->n", n, sig, n)
        p_t = np.einsum("i,nij,j->n", t, sig, n)
        # normal traction undisturbed, shear at the Coulomb bound with the sign of t_T
        np.testing.assert_allclose(p_n, t_n, atol=1e-3 * abs(t_n))
        bound = cohesion + friction * max(0.0, -t_n)
        np.testing.assert_allclose(p_t, math.copysign(bound, t_t), atol=1e-3 * 1e6)


@pytest.mark.parametrize("plane", PLANES)
def test_jump_equals_the_slip_profile(plane):
    t, n = frame()
    s = np.linspace(0.02, 0.98, 25) * 2 * A
    x = s - A
    base = np.asarray(CENTER) + np.outer(x, t)
    up = cf.displacement(base + 1e-10 * n, **field_kw(plane))
    um = cf.displacement(base - 1e-10 * n, **field_kw(plane))
    jump = up - um
    slip = cf.slip_profile(s, A, E, NU, plane, STRESS, PSI, 0.1, 1.0e6)
    np.testing.assert_allclose(jump @ t, slip, rtol=1e-6)
    # no opening (up to the homogeneous strain over the 2e-10 m offset)
    np.testing.assert_allclose(jump @ n, 0.0, atol=1e-6 * np.abs(slip).max())


def test_plane_stress_and_plane_strain_factors():
    s = np.array([0.3, 0.5, 0.7])
    ps = cf.slip_profile(s, A, E, NU, "plane_strain", STRESS, PSI, 0.1)
    pp = cf.slip_profile(s, A, E, NU, "plane_stress", STRESS, PSI, 0.1)
    np.testing.assert_allclose(ps / pp, 1 - NU**2, rtol=1e-12)
    # centre slip 4 (1 - nu^2) / E * dtau * a in plane strain
    dtau = cf.driving_shear(STRESS, PSI, 0.1)
    mid = cf.slip_profile([A], A, E, NU, "plane_strain", STRESS, PSI, 0.1)[0]
    assert mid == pytest.approx(4 * (1 - NU**2) / E * dtau * A, rel=1e-12)
    assert cf.kolosov(NU, "plane_strain") == pytest.approx(3 - 4 * NU)
    assert cf.kolosov(NU, "plane_stress") == pytest.approx((3 - NU) / (1 + NU))
    for plane in PLANES:  # Hooke of the homogeneous strain, both ways
        eps = cf.strain(STRESS, E, NU, plane)
        voigt = np.array([eps[0, 0], eps[1, 1], 2 * eps[0, 1]])
        np.testing.assert_allclose(hooke(plane) @ voigt, STRESS, atol=1e-3)


@pytest.mark.parametrize("plane", PLANES)
def test_far_field_is_the_remote_state(plane):
    t, n = frame()
    far = np.asarray(CENTER) + 1.0e4 * A * np.array([[0.6, 0.8], [-1.0, 0.0]])
    s = cf.stress_field(far, **stress_kw())
    np.testing.assert_allclose(s, np.tile(STRESS, (2, 1)), atol=1e-6 * 40e6)
    # displacement: the homogeneous field plus a perturbation that decays like 1/r
    u = cf.displacement(far, **field_kw(plane))
    u0 = cf.homogeneous_displacement(far, STRESS, E, NU, plane, CENTER)
    assert np.max(np.abs(u - u0)) < 1e-3 * np.max(np.abs(u0))


@pytest.mark.parametrize("end", [+1.0, -1.0])
def test_near_tip_stress_gives_k_ii(end):
    t, n = frame()
    tip = np.asarray(CENTER) + end * A * t
    r = np.array([1e-8, 1e-7]) * A
    pts = tip + np.outer(end * r, t)  # ahead of the tip on the crack line
    s = cf.stress_field(pts, **stress_kw())
    shear = (
        s[:, 0] * t[0] * n[0]
        + s[:, 1] * t[1] * n[1]
        + s[:, 2] * (t[0] * n[1] + t[1] * n[0])
    )
    t_t = cf.crack_tractions(STRESS, PSI)[1]
    k = np.sqrt(2 * np.pi * r) * (shear - t_t)
    # (shear in the crack frame t, n: the sign of K_II is the same at both tips)
    np.testing.assert_allclose(k, cf.k_ii(STRESS, PSI, A, 0.1, 1.0e6), rtol=1e-3)


@pytest.mark.parametrize(
    ("friction", "cohesion"), [(0.1, 0.0), (0.2, 1.0e6), (0.3, 0.0)]
)
def test_slip_window_edges_lie_on_the_coulomb_line(friction, cohesion):
    stress = (-20.0e6, -40.0e6, 5.0e6)
    s1, s3, dir1 = cf.principal(stress)
    assert s1 >= s3 > 0
    lo, hi = cf.slip_window(s1, s3, friction, cohesion)
    assert 0 < lo < hi < 90
    for beta in (lo, hi):
        for sign in (+1, -1):  # both planes at +/- beta from sigma_1
            theta = dir1 + sign * beta
            t_n, t_t = cf.crack_tractions(stress, theta)
            assert abs(t_t) == pytest.approx(cohesion - friction * t_n, rel=1e-9)
            assert cf.angle_to_sigma1(theta, dir1) == pytest.approx(beta)
    # inside the window it slips, just outside it does not
    for beta, slips in ((0.5 * (lo + hi), True), (lo - 0.5, False), (hi + 0.5, False)):
        assert (cf.driving_shear(stress, dir1 + beta, friction, cohesion) != 0) == slips


def test_slip_window_closes_with_large_friction():
    assert cf.slip_window(40e6, 20e6, 1.0) is None  # S = 3 sin(45) > 1


def test_principal_stresses():
    s1, s3, dir1 = cf.principal((-20e6, -40e6, 0.0))
    assert (s1, s3) == (pytest.approx(40e6), pytest.approx(20e6))
    assert dir1 == pytest.approx(90.0)
