"""The interaction integral (xfemslip.post.jintegral) against known fields.

- The Williams auxiliary fields: gradient by finite differences of the
  displacement, stress by Hooke's law of that gradient, traction-free faces.
- The integral itself, fed with exact fields instead of the XFEM ones (the
  displacement gradient at its quadrature points is replaced by the exact
  one): a pure Williams field of given K_I, K_II returns them; the exact
  Westergaard field of the frictional crack, with its exact face tractions,
  returns K_II = dtau sqrt(pi a) and K_I = 0.  This isolates the integral
  from the discretisation error, which the verification tests measure.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.case import build, load_case
from xfemslip.fem.material import elasticity_matrix
from xfemslip.post import jintegral as J
from xfemslip.reference import closed_form as cf
from xfemslip.simulation import build_model
from xfemslip.verify import problems as V

E, NU = V.E, V.NU
MU = E / (2 * (1 + NU))


@pytest.mark.parametrize("plane", ["plane_strain", "plane_stress"])
@pytest.mark.parametrize("mode", [1, 2])
def test_williams_fields_are_consistent(plane, mode):
    kappa = cf.kolosov(NU, plane)
    rng = np.random.default_rng(1)
    r = rng.uniform(0.01, 1.0, 30)
    th = rng.uniform(-3.0, 3.0, 30)
    u, grad, stress = J.williams(r, th, mode, MU, kappa)
    x = np.column_stack([r * np.cos(th), r * np.sin(th)])
    h = 1e-7
    for k, e in enumerate(np.eye(2)):
        xp, xm = x + h * e, x - h * e
        up = J.williams(
            np.hypot(*xp.T), np.arctan2(xp[:, 1], xp[:, 0]), mode, MU, kappa
        )[0]
        um = J.williams(
            np.hypot(*xm.T), np.arctan2(xm[:, 1], xm[:, 0]), mode, MU, kappa
        )[0]
        np.testing.assert_allclose(
            grad[:, :, k],
            (up - um) / (2 * h),
            rtol=1e-5,
            atol=1e-6 * np.abs(grad).max(),
        )
    eps = np.column_stack([grad[:, 0, 0], grad[:, 1, 1], grad[:, 0, 1] + grad[:, 1, 0]])
    sig = eps @ elasticity_matrix(E, NU, plane).T
    np.testing.assert_allclose(sig[:, 0], stress[:, 0, 0], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(sig[:, 1], stress[:, 1, 1], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(sig[:, 2], stress[:, 0, 1], rtol=1e-9, atol=1e-9)
    # faces theta = +/-pi carry no traction: s_12 = s_22 = 0
    _, _, sf = J.williams(
        np.array([0.3, 0.3]), np.array([math.pi, -math.pi]), mode, MU, kappa
    )
    assert np.max(np.abs(sf[:, :, 1])) < 1e-12
    # unit K: s_22 (mode I) or s_12 (mode II) = 1 / sqrt(2 pi r) ahead of the tip
    _, _, sa = J.williams(np.array([0.01]), np.array([0.0]), mode, MU, kappa)
    val = sa[0, 1, 1] if mode == 1 else sa[0, 0, 1]
    assert val == pytest.approx(1 / math.sqrt(2 * math.pi * 0.01))


class _Tractions:
    """A contact result with given tractions at every interface point (the
    fields post.fracture_fields reads, under both of their names)."""

    def __init__(self, pn, pt):
        zero = np.zeros_like(pn)
        self.pn, self.pt, self.gn, self.gt = pn, pt, zero, zero
        self.state = np.zeros(pn.size, np.int8)
        self.point_pn, self.point_pt, self.point_gn, self.point_gt = pn, pt, zero, zero
        self.point_state = self.state
        self.point_plastic_slip = zero


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """The model (mesh, enrichment, quadrature; not solved) of the frictional
    crack at 30 deg with h = a/20: the exact-field tests need only its rules."""
    folder = tmp_path_factory.mktemp("jint")
    prob = V.Problem("inclined-30", 30.0, friction=0.1, cohesion=1.0e6)
    model = build_model(load_case(V.write_case(folder, 80, prob, None, V.PENALTY)))
    u = np.zeros(model.problem.n_dofs)
    n = model.ip.n
    return prob, V.Solved(model, u, _Tractions(np.zeros(n), np.zeros(n)), 0, 0.0)


def _exact_gradient(field):
    """A stand-in for displacement_gradient returning field(xy) at its points."""
    original = J.displacement_gradient

    def grad(model, u, cells):
        xy, w, own, _ = original(model, u, cells)
        return xy, w, own, field(xy)

    return grad


def _tip_frame(tip):
    d = tip.direction
    return np.array([d, [-d[1], d[0]]])


def test_pure_williams_field_returns_its_factors(solved, monkeypatch):
    prob, s = solved
    tip = s.model.fractures[0].tips[1]
    kappa = cf.kolosov(NU, prob.plane)
    K1, K2 = 3.0e6, -5.0e6
    R = _tip_frame(tip)

    def field(xy):
        rel = (xy - tip.point) @ R.T
        r, th = np.hypot(rel[:, 0], rel[:, 1]), np.arctan2(rel[:, 1], rel[:, 0])
        g = (
            K1 * J.williams(r, th, 1, MU, kappa)[1]
            + K2 * J.williams(r, th, 2, MU, kappa)[1]
        )
        return np.einsum("ki,nkl,lj->nij", R, g, R)  # back to x, y

    monkeypatch.setattr(J, "displacement_gradient", _exact_gradient(field))
    zero = _Tractions(np.zeros(s.model.ip.n), np.zeros(s.model.ip.n))
    for radius in (3.0, 5.0):
        out = J.stress_intensity_factors(s.model, s.u, zero, radius_cells=radius)
        k = [t for t in out if t.end == tip.end][0]
        # the integral is exact for this field: only quadrature error remains
        # (measured 1e-7 with 3 and 5 tip cells)
        assert k.k_i == pytest.approx(K1, rel=1e-4)
        assert k.k_ii == pytest.approx(K2, rel=1e-4)


@pytest.mark.parametrize("traction", ["mean", "fit", "interp"])
def test_exact_frictional_crack_gives_closed_form_k(solved, monkeypatch, traction):
    prob, s = solved
    kw = V.exact_kwargs(prob)

    def field(xy):
        h = 1e-7
        g = np.zeros((xy.shape[0], 2, 2))
        for k, e in enumerate(np.eye(2)):
            g[:, :, k] = (
                cf.displacement(xy + h * e, **kw) - cf.displacement(xy - h * e, **kw)
            ) / (2 * h)
        return g

    monkeypatch.setattr(J, "displacement_gradient", _exact_gradient(field))
    t_n, t_t = cf.crack_tractions(V.STRESS, prob.psi)
    n = s.model.ip.n
    exact = _Tractions(np.full(n, t_n), np.full(n, t_t - prob.driving_shear()))
    k_exact = cf.k_ii(V.STRESS, prob.psi, V.HALF_LENGTH, prob.friction, prob.cohesion)
    for t in J.stress_intensity_factors(s.model, s.u, exact, traction=traction):
        # quadrature of the exact field on the h = a/10 XFEM rules: 0.5 %
        assert t.k_ii == pytest.approx(k_exact, rel=5e-3)
        assert abs(t.k_i) < 1e-2 * abs(k_exact)
    # without the crack-face term the friction and the normal compression
    # would be missed: the face term is a sizeable part of the answer
    monkeypatch.setattr(J, "_face_term", lambda *a, **k: np.zeros(2))
    for t in J.stress_intensity_factors(s.model, s.u, exact):
        assert abs(t.k_ii - k_exact) > 0.2 * abs(k_exact) or abs(t.k_i) > 0.2 * abs(
            k_exact
        )


def test_domain_leaving_the_mesh_is_refused(solved):
    _, s = solved
    with pytest.raises(ValueError, match="reaches the mesh boundary"):
        J.stress_intensity_factors(s.model, s.u, s.contact, radius_cells=30.0)
    with pytest.raises(ValueError, match="traction"):
        J.stress_intensity_factors(s.model, s.u, s.contact, traction="raw")


def _reservoir_tip_case(x0) -> str:
    """A 40 m square, the reservoir right of x = x0, a fracture whose upper
    tip (27.7, 25.9) lies in it."""
    return build.case_text(
        {
            "domain": {"size": [40.0, 40.0]},
            "mesh": {"elements": [40, 40]},
            "material": {"E": 20.0e9, "nu": 0.25},
            "reservoir": {"box": [x0, 0.0, 40.0, 40.0], "E": 5.0e9, "nu": 0.35},
            "fractures": [{"points": [[12.3, 14.1], [27.7, 25.9]], "friction": 0.5}],
            "boundary": {"left": {"ux": 0.0}, "bottom": {"uy": 0.0}},
        }
    )


def test_tip_in_the_reservoir_uses_the_reservoir_material(monkeypatch, caplog):
    """A pure Williams field built with the reservoir's E, nu (host: other
    E, nu) returns its K_I, K_II when the tip's domain lies in the reservoir
    (with the host's constants K would be off by the E' and mu ratios); a
    domain across the reservoir edge is refused with a warning."""
    from xfemslip.case import loads_case

    model = build_model(loads_case(_reservoir_tip_case(0.0), "r.toml"))
    tip = model.fractures[0].tips[1]
    mu_r = 5.0e9 / (2 * 1.35)
    kappa = cf.kolosov(0.35, "plane_strain")
    K1, K2 = 2.0e6, -3.0e6
    R = _tip_frame(tip)

    def field(xy):
        rel = (xy - tip.point) @ R.T
        r, th = np.hypot(rel[:, 0], rel[:, 1]), np.arctan2(rel[:, 1], rel[:, 0])
        g = (
            K1 * J.williams(r, th, 1, mu_r, kappa)[1]
            + K2 * J.williams(r, th, 2, mu_r, kappa)[1]
        )
        return np.einsum("ki,nkl,lj->nij", R, g, R)

    monkeypatch.setattr(J, "displacement_gradient", _exact_gradient(field))
    n = model.ip.n
    zero = _Tractions(np.zeros(n), np.zeros(n))
    u = np.zeros(model.problem.n_dofs)
    caplog.set_level("WARNING", logger="xfemslip.post.jintegral")
    out = J.stress_intensity_factors(model, u, zero, radius_cells=3.0)
    k = [t for t in out if t.end == tip.end][0]
    assert k.k_i == pytest.approx(K1, rel=1e-4)
    assert k.k_ii == pytest.approx(K2, rel=1e-4)
    assert "both materials" not in caplog.text
    # reservoir edge x = 25 through the domain of the tip at (27.7, 25.9)
    split = build_model(loads_case(_reservoir_tip_case(25.0), "r.toml"))
    J.stress_intensity_factors(split, u, zero, radius_cells=3.0)
    assert "holds several materials" in caplog.text
