"""Slip-weakening friction in the contact return map (kernels.contact and its
NumPy twin kernels.vectorized).

References: the implicit return written out by hand in each test (softening
modulus H = (c_s - c_d)/D_c + (f_s - f_d)|p_N|/D_c, slip increment
dl = (|p_T trial| - B(delta_old)) / (k_T - H)), central finite differences of
the tractions and of the batched force, and the constant Coulomb law
(static = dynamic) bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from xfemslip.conventions import OPEN, SLIP, STICK, TANGENT_CONSISTENT, TANGENT_SECANT
from xfemslip.kernels import contact, vectorized

KN, KT = 1.0e12, 5.0e11  # [Pa/m]
FS, FD = 0.6, 0.4  # static, dynamic friction [-]
DC = 1.0e-5  # slip distance [m]

BACKENDS = [
    pytest.param(contact.coulomb_return_map, id="numba"),
    pytest.param(
        lambda *a: tuple(
            np.asarray(v).item() for v in vectorized.coulomb_return_map(
                *(np.atleast_1d(np.float64(x)) for x in a)
            )
        ),
        id="numpy",
    ),
]  # fmt: skip


def _rm(rm, gn, gt, slip_old=0.0, acc=0.0, pn0=-2e6, kt=KT, fs=FS, fd=FD, cs=0.0,
        cd=0.0, dc=DC):  # fmt: skip
    return rm(gn, gt, slip_old, acc, pn0, KN, kt, fs, cs, fd, cd, dc)


@pytest.mark.parametrize("rm", BACKENDS)
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_slip_on_the_weakening_branch_by_hand(rm, sign):
    # pn = 1e12 * (-1e-6) - 2e6 = -3e6; trial pt = 5e11 * 5e-6 = 2.5e6
    pn, pt, state, slip, acc, dnn, dnt, dtn, dtt = _rm(rm, -1e-6, sign * 5e-6)
    H = (FS - FD) * 3e6 / DC  # 6e10 Pa/m
    dl = (2.5e6 - FS * 3e6) / (KT - H)  # 1.5909e-6 m < DC: stays on the branch
    f_new = FS - (FS - FD) * dl / DC
    assert state == SLIP
    assert pn == pytest.approx(-3e6, rel=1e-15)
    assert pt == pytest.approx(sign * f_new * 3e6, rel=1e-13)
    # the elastic traction from the new plastic slip is the same traction
    assert pt == pytest.approx(KT * (sign * 5e-6 - slip), rel=1e-12)
    assert slip == pytest.approx(sign * dl, rel=1e-12)
    assert acc == pytest.approx(dl, rel=1e-12)
    assert (dnn, dnt) == (KN, 0.0)
    assert dtt == pytest.approx(-H * KT / (KT - H), rel=1e-13)
    assert dtn == pytest.approx(-sign * f_new * KN * KT / (KT - H), rel=1e-13)


@pytest.mark.parametrize("rm", BACKENDS)
def test_slip_past_the_weakening_range_lands_on_the_dynamic_bound(rm):
    # delta_old = 0.9 D_c: f = 0.42, bound 1.26e6; the weakening branch would
    # need dl = (2.5e6 - 1.26e6) / (KT - H) = 2.8e-6 > 0.1 D_c left: the slip
    # passes D_c and returns on the dynamic bound f_d |p_N| = 1.2e6
    pn, pt, state, slip, acc, dnn, dnt, dtn, dtt = _rm(rm, -1e-6, 5e-6, acc=0.9 * DC)
    assert state == SLIP
    assert pt == pytest.approx(FD * 3e6, rel=1e-14)
    assert acc == pytest.approx(0.9 * DC + (2.5e6 - 1.2e6) / KT, rel=1e-13)
    assert (dtn, dtt) == (pytest.approx(-FD * KN, rel=1e-15), 0.0)
    # from beyond D_c on, the law is Coulomb with the dynamic values
    out = _rm(rm, -1e-6, 5e-6, acc=2.0 * DC)
    assert out[1] == pytest.approx(FD * 3e6, rel=1e-14)
    assert out[4] == pytest.approx(2.0 * DC + (2.5e6 - 1.2e6) / KT, rel=1e-13)


@pytest.mark.parametrize("rm", BACKENDS)
def test_cohesion_weakens_over_the_same_distance(rm):
    # c 1e6 -> 0.2e6, friction constant 0.5: H = 0.8e6 / DC = 8e10 Pa/m
    cs, cd = 1e6, 0.2e6
    pn, pt, state, slip, acc, *_, dtt = _rm(
        rm, -1e-6, 6e-6, acc=0.25 * DC, fs=0.5, fd=0.5, cs=cs, cd=cd
    )
    c_old = cs - (cs - cd) * 0.25
    bound = c_old + 0.5 * 3e6
    H = (cs - cd) / DC
    dl = (3e6 - bound) / (KT - H)
    assert state == SLIP
    assert pt == pytest.approx(c_old - H * dl + 0.5 * 3e6, rel=1e-13)
    assert acc == pytest.approx(0.25 * DC + dl, rel=1e-12)
    assert dtt == pytest.approx(-H * KT / (KT - H), rel=1e-13)


@pytest.mark.parametrize("rm", BACKENDS)
def test_stick_open_and_history_keep_the_accumulated_slip(rm):
    # stick: trial 1e6 below the bound 0.5 * 3e6 (delta_old = 0.5 D_c: f = 0.5)
    pn, pt, state, slip, acc, *_ = _rm(rm, -1e-6, 3e-6, slip_old=1e-6, acc=0.5 * DC)
    assert (state, slip, acc) == (STICK, 1e-6, 0.5 * DC)
    assert pt == pytest.approx(1e6, rel=1e-12)
    # the same trial 1.6e6 sticks with f = 0.6 and slips with f = 0.5
    assert _rm(rm, -1e-6, 3.2e-6)[2] == STICK
    assert _rm(rm, -1e-6, 3.2e-6, acc=0.5 * DC)[2] == SLIP
    # open faces do not slide on each other: no frictional slip accumulates
    pn, pt, state, slip, acc, *_ = _rm(rm, 3e-6, 9e-6, acc=0.3 * DC)
    assert (state, pn, pt, slip, acc) == (OPEN, 0.0, 0.0, 9e-6, 0.3 * DC)


def test_accumulated_slip_adds_the_magnitudes_of_forward_and_backward_slip():
    """delta = int |d g_T^p| over a path out and back (two committed steps)."""
    rm = contact.coulomb_return_map
    # step 1: forward slip from zero
    out1 = _rm(rm, -1e-6, 5e-6)
    # step 2: back past the stick band, slipping backward
    out2 = _rm(rm, -1e-6, -5e-6, slip_old=out1[3], acc=out1[4])
    assert out1[2] == out2[2] == SLIP
    assert out2[1] < 0.0
    assert out2[4] == pytest.approx(abs(out1[3]) + abs(out2[3] - out1[3]), rel=1e-12)
    assert out2[3] < 0.0 < out1[3]


@pytest.mark.parametrize("rm", BACKENDS)
def test_a_penalty_softer_than_the_weakening(rm):
    """k_T <= H: no root on the weakening branch.  Outside the bound the one
    root with dl >= 0 is on the dynamic branch (the traction drops at once);
    inside it the point sticks (the elastic predictor)."""
    kt = 5e10  # H = 6e10 at p_N = -3e6
    pn, pt, state, slip, acc, *_ = _rm(rm, -1e-6, 4e-5, kt=kt)  # trial 2e6 > 1.8e6
    assert state == SLIP
    assert pt == pytest.approx(FD * 3e6, rel=1e-14)
    assert acc == pytest.approx((2e6 - FD * 3e6) / kt, rel=1e-13)
    assert acc > DC  # the whole weakening range, in one return
    out = _rm(rm, -1e-6, 3.5e-5, kt=kt)  # trial 1.75e6 <= 1.8e6
    assert out[2] == STICK and out[4] == 0.0


def _tangent(out):
    return np.array([[out[5], out[6]], [out[7], out[8]]])


def _fd(rm, gn, gt, h=1e-12, **kw):
    J = np.zeros((2, 2))
    for k, (dgn, dgt) in enumerate(((h, 0.0), (0.0, h))):
        p = _rm(rm, gn + dgn, gt + dgt, **kw)
        m = _rm(rm, gn - dgn, gt - dgt, **kw)
        J[:, k] = [(p[0] - m[0]) / (2 * h), (p[1] - m[1]) / (2 * h)]
    return J


@pytest.mark.parametrize("rm", BACKENDS)
@pytest.mark.parametrize(
    "gn, gt, kw",
    [
        (-1e-6, 5e-6, {}),  # weakening branch, forward
        (-1e-6, -5e-6, {}),  # backward
        (-2.5e-6, 4e-6, {"slip_old": 1e-6, "acc": 0.3 * DC}),
        (-1e-6, 6e-6, {"acc": 0.25 * DC, "cs": 1e6, "cd": 0.2e6}),  # + cohesion
        (-1e-6, 5e-6, {"acc": 0.9 * DC}),  # past D_c in this return
        (-1e-6, 5e-6, {"acc": 2.0 * DC}),  # dynamic
        (-1e-6, 4e-5, {"kt": 5e10}),  # k_T <= H
        (-1e-6, 3e-6, {"slip_old": 1e-6, "acc": 0.5 * DC}),  # stick
    ],
)
def test_consistent_tangent_equals_central_differences(rm, gn, gt, kw):
    """Including the n-t coupling through p_N: d p_T / d g_N = -f_new k_N
    k_T / (k_T - H) on the weakening branch (f and H both follow p_N)."""
    out = _rm(rm, gn, gt, **kw)
    fd = _fd(rm, gn, gt, **kw)
    np.testing.assert_allclose(_tangent(out), fd, rtol=1e-6, atol=1e-6 * KT)
    if out[2] == SLIP and out[4] < DC:
        assert out[8] < 0.0  # softening while the slip ends within D_c


@pytest.mark.parametrize("rm", BACKENDS)
def test_equal_static_and_dynamic_values_are_coulomb_bit_for_bit(rm):
    rng = np.random.default_rng(3)
    for _ in range(200):
        gn, gt = rng.normal(0.0, 2e-6), rng.normal(0.0, 1e-5)
        slip_old, pn0 = rng.normal(0.0, 5e-6), -rng.uniform(0.0, 5e6)
        f, c = rng.uniform(0.0, 0.9), rng.uniform(0.0, 1e6) * (rng.random() < 0.5)
        acc = rng.uniform(0.0, 3e-3)
        coulomb = rm(gn, gt, slip_old, 0.0, pn0, KN, KT, f, c, f, c, np.inf)
        law = rm(gn, gt, slip_old, acc, pn0, KN, KT, f, c, f, c, 1e-3)
        assert coulomb[:4] == law[:4]
        assert coulomb[5:] == law[5:]


def _batched(u, d, mode, backend=contact):
    n, J = d["coef"].shape
    out = [np.zeros((n, 2 * J)), np.zeros((n, 2 * J, 2 * J))]
    out += [np.zeros(n) for _ in range(4)] + [np.zeros(n, np.int8)]
    out += [np.zeros(n), np.zeros(n)]
    backend.contact_response(
        u, d["dofs"], d["coef"], d["normal"], d["tangent"], d["weight"],
        d["pn0"], d["slip_old"], d["acc"], d["kn"], d["kt"], d["fs"], d["cs"],
        d["fd"], d["cd"], d["dc"], mode, d["pt_prev"], d["gt_prev"], *out,
    )  # fmt: skip
    return dict(
        zip(
            ("f", "K", "gn", "gt", "pn", "pt", "state", "slip", "acc"), out, strict=True
        )
    )


def _points(rng, n=60, J=3, n_dofs=20):
    ang = rng.uniform(0, 2 * np.pi, n)
    tangent = np.column_stack([np.cos(ang), np.sin(ang)])
    fs = rng.uniform(0.3, 0.8, n)
    dc = rng.uniform(5e-6, 5e-5, n)
    return {
        "dofs": rng.integers(0, n_dofs, size=(n, 2 * J)).astype(np.int64),
        "coef": rng.uniform(-1.0, 2.0, (n, J)),
        "normal": np.column_stack([-tangent[:, 1], tangent[:, 0]]),
        "tangent": tangent,
        "weight": rng.uniform(0.01, 0.1, n),
        "pn0": -rng.uniform(1e6, 5e6, n),
        "slip_old": rng.normal(0.0, 2e-6, n),
        "acc": rng.uniform(0.0, 1.2, n) * dc,
        "kn": rng.uniform(0.5, 2.0, n) * 1e12,
        "kt": rng.uniform(0.5, 2.0, n) * 1e12,
        "fs": fs,
        "cs": rng.uniform(0.0, 1e6, n),
        "fd": fs * rng.uniform(0.3, 0.9, n),
        "cd": np.zeros(n),
        "dc": dc,
        "pt_prev": rng.normal(0.0, 1e6, n),
        "gt_prev": rng.normal(0.0, 5e-6, n),
        "n_dofs": n_dofs,
    }


def _assemble(out, d):
    f = np.zeros(d["n_dofs"])
    np.add.at(f, d["dofs"].ravel(), out["f"].ravel())
    return f


def test_batched_tangent_equals_central_differences_of_the_force():
    rng = np.random.default_rng(21)
    d = _points(rng)
    u = rng.normal(0.0, 4e-6, d["n_dofs"])
    base = _batched(u, d, TANGENT_CONSISTENT)
    # drop the points near a switching surface (FD would straddle it): the
    # stick/slip test, the end of the weakening range and opening
    pn = base["pn"]
    trial = d["kt"] * (base["gt"] - d["slip_old"])
    f_old = vectorized.weakened(d["fs"], d["fd"], d["acc"], d["dc"])
    c_old = vectorized.weakened(d["cs"], d["cd"], d["acc"], d["dc"])
    bound = c_old - f_old * pn
    end = np.abs(base["acc"] - d["dc"]) > 1e-3 * d["dc"]
    keep = (pn < -1e4) & (np.abs(np.abs(trial) - bound) > 1e4) & end
    d = {k: (v[keep] if isinstance(v, np.ndarray) else v) for k, v in d.items()}
    base = _batched(u, d, TANGENT_CONSISTENT)
    on_branch = (base["state"] == SLIP) & (base["acc"] < d["dc"])
    assert on_branch.sum() >= 5 and np.any(base["acc"] > d["dc"])
    K = np.zeros((d["n_dofs"], d["n_dofs"]))
    rows = np.repeat(d["dofs"][:, :, None], d["dofs"].shape[1], axis=2)
    cols = np.repeat(d["dofs"][:, None, :], d["dofs"].shape[1], axis=1)
    np.add.at(K, (rows.ravel(), cols.ravel()), base["K"].ravel())
    h = 1e-12
    fd = np.zeros_like(K)
    for j in range(d["n_dofs"]):
        e = np.zeros(d["n_dofs"])
        e[j] = h
        fp = _assemble(_batched(u + e, d, TANGENT_CONSISTENT), d)
        fm = _assemble(_batched(u - e, d, TANGENT_CONSISTENT), d)
        fd[:, j] = (fp - fm) / (2 * h)
    scale = np.abs(K).max()
    np.testing.assert_allclose(K, fd, rtol=0, atol=1e-5 * scale)
    # the NumPy twin gives the same forces and tangent
    twin = _batched(u, d, TANGENT_CONSISTENT, vectorized)
    for key in ("f", "K", "pt", "slip", "acc"):
        np.testing.assert_allclose(twin[key], base[key], rtol=1e-12, atol=1e-9)


def test_secant_mode_keeps_the_consistent_tangent_on_a_weakening_branch():
    """The secant of a softening branch is positive (|Delta p_T| / |Delta g_T|),
    the wrong sign: weakening points keep d p_T / d g_T < 0; Coulomb points
    (at and past D_c) get the secant as before."""
    rng = np.random.default_rng(8)
    d = _points(rng, n=80)
    u = rng.normal(0.0, 4e-6, d["n_dofs"])
    for backend in (contact, vectorized):
        cons = _batched(u, d, TANGENT_CONSISTENT, backend)
        sec = _batched(u, d, TANGENT_SECANT, backend)
        slipping = cons["state"] == SLIP
        branch = slipping & (cons["acc"] < d["dc"])
        assert branch.any() and (slipping & ~branch).any()
        np.testing.assert_array_equal(cons["K"][branch], sec["K"][branch])
        assert not np.allclose(
            cons["K"][slipping & ~branch], sec["K"][slipping & ~branch]
        )
