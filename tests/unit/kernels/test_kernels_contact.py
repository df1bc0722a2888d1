"""Tests of xfemslip.kernels.contact: the Coulomb return map and the batched loop.

References: values by hand in each branch (open, stick, slip; cohesion; in-situ
normal traction pn0), central finite differences of the tractions and of the
batched force, and a plain NumPy loop written here.
"""

from __future__ import annotations

import numpy as np
import pytest

from xfemslip.conventions import OPEN, SLIP, STICK, TANGENT_CONSISTENT, TANGENT_SECANT
from xfemslip.kernels.contact import contact_response, coulomb_return_map

KN, KT = 1.0e12, 5.0e11  # [Pa/m]
F, C = 0.5, 0.2e6  # friction [-], cohesion [Pa]


def _rm(gn, gt, slip_old=0.0, pn0=0.0, kn=KN, kt=KT, f=F, c=C):
    """The return map of constant Coulomb friction (no accumulated slip, f_d
    = f, c_d = c, D_c = inf): (pn, pt, state, slip, d_nn, d_nt, d_tn, d_tt)."""
    out = coulomb_return_map(gn, gt, slip_old, 0.0, pn0, kn, kt, f, c, f, c, np.inf)
    return out[:4] + out[5:]


# ---------------------------------------------------------------- scalar return map


def test_open_branch():
    # pn = kn gn + pn0 = 2e6 - 1e6 > 0: open, no traction, the slip follows gt
    pn, pt, state, slip, dnn, dnt, dtn, dtt = _rm(2e-6, 3e-6, slip_old=1e-6, pn0=-1e6)
    assert state == OPEN
    assert (pn, pt, dnn, dnt, dtn, dtt) == (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert slip == 3e-6
    # opening without in-situ traction: any positive gap
    assert _rm(1e-12, 0.0)[2] == OPEN
    # a compressive in-situ traction keeps a small opening closed: pn = 1e3 - 1e6 < 0
    assert _rm(1e-9, 0.0, pn0=-1e6)[2] != OPEN


def test_stick_branch_by_hand():
    # pn = 1e12 * (-1e-6) - 2e6 = -3e6; pt_trial = 5e11 * (3e-6 - 1e-6) = 1e6
    # bound = c - f pn = 0.2e6 + 1.5e6 = 1.7e6 > 1e6: stick
    pn, pt, state, slip, dnn, dnt, dtn, dtt = _rm(-1e-6, 3e-6, slip_old=1e-6, pn0=-2e6)
    assert state == STICK
    assert pn == pytest.approx(-3e6, rel=1e-15)
    assert pt == pytest.approx(1e6, rel=1e-12)
    assert slip == 1e-6
    assert (dnn, dnt, dtn, dtt) == (KN, 0.0, 0.0, KT)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_slip_branch_by_hand(sign):
    # same pn = -3e6, bound 1.7e6; pt_trial = 5e11 * (+-6e-6 -+ 1e-6) = +-2.5e6: slip
    gt = sign * 6e-6
    pn, pt, state, slip, dnn, dnt, dtn, dtt = _rm(
        -1e-6, gt, slip_old=sign * 1e-6, pn0=-2e6
    )
    assert state == SLIP
    assert pn == pytest.approx(-3e6, rel=1e-15)
    assert pt == pytest.approx(sign * 1.7e6, rel=1e-14)
    # plastic slip: gt - pt / kt = +-(6e-6 - 3.4e-6)
    assert slip == pytest.approx(sign * 2.6e-6, rel=1e-12)
    assert (dnn, dnt, dtt) == (KN, 0.0, 0.0)
    assert dtn == pytest.approx(-sign * F * KN, rel=1e-15)


def test_cohesion_alone_holds_at_zero_normal_traction():
    # gn = 0, pn0 = 0: pn = 0 (closed, not open); the bound is the cohesion
    pn, pt, state, *_ = _rm(0.0, 0.3e-6)  # pt_trial = 0.15e6 < 0.2e6
    assert (pn, state) == (0.0, STICK)
    assert pt == pytest.approx(0.15e6, rel=1e-12)
    pn, pt, state, *_ = _rm(0.0, 1e-6)  # pt_trial = 0.5e6 > 0.2e6
    assert state == SLIP
    assert pt == pytest.approx(C, rel=1e-15)
    # without cohesion nor friction the faces slide freely
    pn, pt, state, slip, *_ = _rm(-1e-6, 1e-6, f=0.0, c=0.0)
    assert (pt, state) == (0.0, SLIP)
    assert slip == 1e-6


def test_in_situ_normal_traction_closes_the_faces_at_zero_jump():
    # pn = pn0 = -4e6 at gn = 0: bound = 0.2e6 + 2e6 = 2.2e6
    pn, pt, state, *_ = _rm(0.0, 0.0, slip_old=-4e-6, pn0=-4e6)  # pt_trial = 2e6
    assert (pn, state) == (-4e6, STICK)
    assert pt == pytest.approx(2e6, rel=1e-12)
    pn, pt, state, *_ = _rm(0.0, 0.0, slip_old=-5e-6, pn0=-4e6)  # pt_trial = 2.5e6
    assert state == SLIP
    assert pt == pytest.approx(2.2e6, rel=1e-14)


@pytest.mark.parametrize("gt", [6e-6, -9e-6, 2e-5, 4.5e-6])
@pytest.mark.parametrize("c", [0.0, C])
def test_slip_lands_on_the_cone_and_is_idempotent(gt, c):
    gn, pn0, slip_old = -1e-6, -2e6, 1e-6
    pn, pt, state, slip, *_ = _rm(gn, gt, slip_old, pn0, c=c)
    assert state == SLIP
    assert abs(pt) == pytest.approx(c - F * pn, rel=1e-14)
    assert np.sign(pt) == np.sign(gt - slip_old)
    # returning again from the returned state does nothing
    pn2, pt2, state2, slip2, *_ = _rm(gn, gt, slip, pn0, c=c)
    assert state2 in (STICK, SLIP)  # on the cone: either, up to round-off
    assert pn2 == pn
    assert pt2 == pytest.approx(pt, rel=1e-12)
    assert slip2 == pytest.approx(slip, rel=1e-12, abs=1e-20)


def _fd_tangent(gn, gt, slip_old, pn0, h=1e-12):
    J = np.zeros((2, 2))
    for k, (dgn, dgt) in enumerate(((h, 0.0), (0.0, h))):
        p = _rm(gn + dgn, gt + dgt, slip_old, pn0)
        m = _rm(gn - dgn, gt - dgt, slip_old, pn0)
        J[0, k] = (p[0] - m[0]) / (2 * h)
        J[1, k] = (p[1] - m[1]) / (2 * h)
    return J


@pytest.mark.parametrize(
    "gn, gt, slip_old, pn0, state",
    [
        (2e-6, 3e-6, 1e-6, -1e6, OPEN),
        (-1e-6, 3e-6, 1e-6, -2e6, STICK),
        (-1e-6, -1e-6, 1e-6, -2e6, STICK),
        (-1e-6, 6e-6, 1e-6, -2e6, SLIP),
        (-1e-6, -6e-6, 1e-6, -2e6, SLIP),
        (-3e-6, 1e-5, 0.0, 0.0, SLIP),
    ],
)
def test_consistent_tangent_equals_central_differences(gn, gt, slip_old, pn0, state):
    out = _rm(gn, gt, slip_old, pn0)
    assert out[2] == state
    tangent = np.array([[out[4], out[5]], [out[6], out[7]]])
    fd = _fd_tangent(gn, gt, slip_old, pn0)
    np.testing.assert_allclose(tangent, fd, rtol=0, atol=1e-6 * KN)


# ------------------------------------------------------------------ batched kernel


def return_map_reference(gn, gt, slip_old, pn0, kn, kt, f, c):
    """Penalty + Coulomb return map in plain Python (house-style signs)."""
    pn = kn * gn + pn0
    if pn > 0.0:
        return 0.0, 0.0, OPEN, gt, np.zeros((2, 2))
    trial = kt * (gt - slip_old)
    bound = c - f * pn
    if abs(trial) <= bound:
        return pn, trial, STICK, slip_old, np.array([[kn, 0.0], [0.0, kt]])
    s = np.sign(trial)
    pt = s * bound
    return pn, pt, SLIP, gt - pt / kt, np.array([[kn, 0.0], [-s * f * kn, 0.0]])


def response_reference(u, d, mode):
    """Plain loop over points: jump, tractions, force and tangent blocks."""
    n, J = d["coef"].shape
    out = {k: np.zeros(n) for k in ("gn", "gt", "pn", "pt", "slip")}
    out["state"] = np.zeros(n, np.int8)
    out["f"] = np.zeros((n, 2 * J))
    out["K"] = np.zeros((n, 2 * J, 2 * J))
    for i in range(n):
        jump = np.zeros(2)
        for k in range(J):
            for comp in range(2):
                dof = d["dofs"][i, 2 * k + comp]
                if dof >= 0:
                    jump[comp] += d["coef"][i, k] * u[dof]
        nrm, tan = d["normal"][i], d["tangent"][i]
        gn, gt = jump @ nrm, jump @ tan
        pn, pt, state, slip, T = return_map_reference(
            gn,
            gt,
            d["slip_old"][i],
            d["pn0"][i],
            d["kn"][i],
            d["kt"][i],
            d["friction"][i],
            d["cohesion"][i],
        )
        if mode == TANGENT_SECANT and state == SLIP:
            dg = abs(gt - d["gt_prev"][i])
            dtt = (
                d["kt"][i]
                if dg == 0.0
                else min(abs(pt - d["pt_prev"][i]) / dg, d["kt"][i])
            )
            T = np.array([[T[0, 0], T[0, 1]], [0.0, dtt]])
        # traction p_n n + p_t t; its derivative w.r.t. the jump, from the (n, t)
        # frame to (x, y)
        Q = np.column_stack([nrm, tan])  # columns n, t
        Cxy = Q @ T @ Q.T
        trac = pn * nrm + pt * tan
        for k in range(J):
            out["f"][i, 2 * k : 2 * k + 2] = d["weight"][i] * d["coef"][i, k] * trac
            for m in range(J):
                out["K"][i, 2 * k : 2 * k + 2, 2 * m : 2 * m + 2] = (
                    d["weight"][i] * d["coef"][i, k] * d["coef"][i, m] * Cxy
                )
        for key, val in (
            ("gn", gn),
            ("gt", gt),
            ("pn", pn),
            ("pt", pt),
            ("slip", slip),
            ("state", state),
        ):
            out[key][i] = val
    return out


def _random_data(rng, n=60, J=3, n_dofs=25):
    ang = rng.uniform(0, 2 * np.pi, n)
    tangent = np.column_stack([np.cos(ang), np.sin(ang)])
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    dofs = rng.integers(-1, n_dofs, size=(n, 2 * J))
    return {
        "dofs": dofs.astype(np.int64),
        "coef": rng.uniform(-1.0, 2.0, (n, J)),
        "normal": normal,
        "tangent": tangent,
        "weight": rng.uniform(0.01, 0.1, n),
        "pn0": np.where(rng.random(n) < 0.5, 0.0, -rng.uniform(0, 5e6, n)),
        "slip_old": rng.normal(0.0, 2e-6, n),
        "kn": rng.uniform(0.5, 2.0, n) * 1e12,
        "kt": rng.uniform(0.5, 2.0, n) * 1e12,
        "friction": rng.uniform(0.0, 0.8, n),
        "cohesion": np.where(rng.random(n) < 0.5, 0.0, rng.uniform(0, 1e6, n)),
        "pt_prev": rng.normal(0.0, 1e6, n),
        "gt_prev": rng.normal(0.0, 5e-6, n),
        "n_dofs": n_dofs,
    }


def _call(u, d, mode):
    n, J = d["coef"].shape
    out = {"f": np.zeros((n, 2 * J)), "K": np.zeros((n, 2 * J, 2 * J))}
    for k in ("gn", "gt", "pn", "pt", "slip"):
        out[k] = np.zeros(n)
    out["state"] = np.zeros(n, np.int8)
    contact_response(
        u,
        d["dofs"],
        d["coef"],
        d["normal"],
        d["tangent"],
        d["weight"],
        d["pn0"],
        d["slip_old"],
        np.zeros(n),
        d["kn"],
        d["kt"],
        d["friction"],
        d["cohesion"],
        d["friction"],
        d["cohesion"],
        np.full(n, np.inf),
        mode,
        d["pt_prev"],
        d["gt_prev"],
        out["f"],
        out["K"],
        out["gn"],
        out["gt"],
        out["pn"],
        out["pt"],
        out["state"],
        out["slip"],
        np.zeros(n),
    )
    return out


@pytest.mark.parametrize(
    "mode", [TANGENT_CONSISTENT, TANGENT_SECANT], ids=["consistent", "secant"]
)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_contact_response_equals_the_numpy_loop(mode, seed):
    rng = np.random.default_rng(seed)
    d = _random_data(rng)
    u = rng.normal(0.0, 4e-6, d["n_dofs"])
    inputs = {k: np.copy(v) for k, v in d.items()}
    u_in = u.copy()
    got = _call(u, d, mode)
    ref = response_reference(u, d, mode)
    # all three branches are exercised
    assert set(np.unique(got["state"])) == {OPEN, STICK, SLIP}
    np.testing.assert_array_equal(got["state"], ref["state"])
    for key in ("gn", "gt"):
        np.testing.assert_allclose(got[key], ref[key], rtol=1e-12, atol=1e-22)
    for key in ("pn", "pt"):
        np.testing.assert_allclose(got[key], ref[key], rtol=1e-10, atol=1e-6)
    np.testing.assert_allclose(got["slip"], ref["slip"], rtol=1e-10, atol=1e-20)
    np.testing.assert_allclose(got["f"], ref["f"], rtol=1e-10, atol=1e-6)
    np.testing.assert_allclose(got["K"], ref["K"], rtol=1e-10, atol=1e-2)
    # inputs are not modified (only out_* arrays are written)
    np.testing.assert_array_equal(u, u_in)
    for k, v in inputs.items():
        np.testing.assert_array_equal(d[k], v)


def test_secant_equals_consistent_except_while_slipping():
    rng = np.random.default_rng(5)
    d = _random_data(rng)
    u = rng.normal(0.0, 4e-6, d["n_dofs"])
    cons = _call(u, d, TANGENT_CONSISTENT)
    sec = _call(u, d, TANGENT_SECANT)
    for key in ("f", "pn", "pt", "gn", "gt", "slip", "state"):
        np.testing.assert_array_equal(cons[key], sec[key])
    not_slip = cons["state"] != SLIP
    np.testing.assert_array_equal(cons["K"][not_slip], sec["K"][not_slip])
    assert not np.allclose(cons["K"][~not_slip], sec["K"][~not_slip])


def _assemble(out, d):
    n_dofs = d["n_dofs"]
    f = np.zeros(n_dofs)
    K = np.zeros((n_dofs, n_dofs))
    dofs = d["dofs"]
    for i in range(dofs.shape[0]):
        for a in range(dofs.shape[1]):
            if dofs[i, a] < 0:
                continue
            f[dofs[i, a]] += out["f"][i, a]
            for b in range(dofs.shape[1]):
                if dofs[i, b] >= 0:
                    K[dofs[i, a], dofs[i, b]] += out["K"][i, a, b]
    return f, K


def test_batched_tangent_equals_central_differences_of_the_force():
    rng = np.random.default_rng(11)
    d = _random_data(rng, n=80)
    u = rng.normal(0.0, 4e-6, d["n_dofs"])
    base = _call(u, d, TANGENT_CONSISTENT)
    # drop the points within a margin of a switching surface (FD would straddle it)
    trial_pn = d["kn"] * base["gn"] + d["pn0"]
    trial_pt = d["kt"] * (base["gt"] - d["slip_old"])
    bound = d["cohesion"] - d["friction"] * trial_pn
    keep = (np.abs(trial_pn) > 1e4) & (np.abs(np.abs(trial_pt) - bound) > 1e4)
    d = {k: (v[keep] if isinstance(v, np.ndarray) else v) for k, v in d.items()}
    base = _call(u, d, TANGENT_CONSISTENT)
    assert set(np.unique(base["state"])) == {OPEN, STICK, SLIP}
    _, K = _assemble(base, d)
    h = 1e-12  # [m]; |coef| <= 2 so the jump moves < 1e-11, the pressures < 2e1 Pa
    fd = np.zeros_like(K)
    for j in range(d["n_dofs"]):
        e = np.zeros(d["n_dofs"])
        e[j] = h
        fp, _ = _assemble(_call(u + e, d, TANGENT_CONSISTENT), d)
        fm, _ = _assemble(_call(u - e, d, TANGENT_CONSISTENT), d)
        fd[:, j] = (fp - fm) / (2 * h)
    scale = np.abs(K).max()
    assert scale > 1e9
    np.testing.assert_allclose(K, fd, rtol=0, atol=1e-5 * scale)
    # the consistent tangent is not symmetric while slipping (f kn coupling)
    assert np.abs(K - K.T).max() > 1e-3 * scale


def test_jump_uses_both_components_and_ignores_absent_dofs():
    """One point, J = 2: [[u]] = c0 (u[3], u[4]) + c1 (u[-1 -> absent], u[0])."""
    d = _random_data(np.random.default_rng(0), n=1, J=2, n_dofs=5)
    d["dofs"] = np.array([[3, 4, -1, 0]], np.int64)
    d["coef"] = np.array([[2.0, -0.5]])
    d["normal"] = np.array([[0.0, 1.0]])
    d["tangent"] = np.array([[1.0, 0.0]])
    d["pn0"] = np.zeros(1)
    u = np.array([1e-6, 0.0, 0.0, 3e-6, -2e-6])
    out = _call(u, d, TANGENT_CONSISTENT)
    # jump = (2 * 3e-6, 2 * (-2e-6) - 0.5 * 1e-6) = (6e-6, -4.5e-6)
    assert out["gt"][0] == pytest.approx(6e-6, rel=1e-14)
    assert out["gn"][0] == pytest.approx(-4.5e-6, rel=1e-14)
    assert out["pn"][0] == pytest.approx(-4.5e-6 * d["kn"][0], rel=1e-14)
