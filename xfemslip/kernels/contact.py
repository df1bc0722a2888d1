"""Penalty contact with Coulomb friction and cohesion at fracture integration points.

Layering (house style): a scalar return map ``coulomb_return_map`` and a batched
loop ``contact_response`` over the interface points; the Python driver is
``xfemslip/contact/interface.py``.  No fastmath here: the law is made of sign tests.

Signs (tension positive): p_N = k_N g_N + p_N0 <= 0 in contact (paper eqs. 5-6,
with p_N0 the in-situ normal traction), open when that is > 0 (no traction);
Coulomb bound |p_T| <= c_f - f p_N (eqs. 7-8); trial p_T = k_T (g_T - g_T^p)
with g_T^p the committed plastic slip (eq. 26), returned onto the bound when it
is exceeded (eqs. 27-28).

Slip weakening (docs/method.md, *Slip-weakening friction*): f and c_f fall
linearly from their static to their dynamic values over the slip distance D_c
of accumulated slip delta = int |d g_T^p| (frictional slip of closed faces),

    f(delta) = f_s - (f_s - f_d) min(delta / D_c, 1),  likewise c_f(delta).

The bound B(delta) = c_f(delta) - f(delta) p_N then softens with the slip
increment dl >= 0 of the return at the rate H = (c_s - c_d)/D_c +
(f_s - f_d) |p_N| / D_c [Pa/m] while delta < D_c, so the return is implicit
but linear: |p_T trial| - k_T dl = B(delta_old) - H dl gives
dl = (|p_T trial| - B(delta_old)) / (k_T - H).  When that dl passes the end of
the weakening range (delta_old + dl > D_c), the bound is the dynamic one and
dl = (|p_T trial| - B_d) / k_T.  With k_T <= H the return has no root on the
weakening branch: from a trial outside the bound the one root with dl >= 0
is on the dynamic branch past D_c (taken: the traction drops to the dynamic
bound at once), and from a trial inside it stick, a root on the weakening
branch and one past D_c all satisfy the law (stick is taken: the elastic
predictor, the state the point is in).  k_T <= H means the point's own
penalty spring is softer than its weakening, a snap-back that the body,
whose stiffness is in series with k_T, has already passed as a loss of
equilibrium (docs/method.md).  A law whose static and dynamic values are equal
takes the Coulomb return unchanged, bit for bit.
"""

import numpy as np
from numba import njit

from xfemslip.conventions import OPEN, SLIP, STICK, TANGENT_SECANT
from xfemslip.kernels._config import NUMBA_CACHE, SECANT_MIN_INCREMENT


@njit(cache=NUMBA_CACHE)
def weakened(static, dynamic, accumulated, slip_distance):
    """Linearly slip-weakened value of a strength parameter (f or c_f):
    ``static`` at zero accumulated slip, ``dynamic`` from ``slip_distance``
    [m] of it on.  Equal values give ``static`` itself (also when both are
    infinite: a patch held in stick, contact.branches.force_branches)."""
    if static == dynamic or accumulated <= 0.0:
        return static
    if accumulated >= slip_distance:
        return dynamic
    return static - (static - dynamic) * (accumulated / slip_distance)


@njit(cache=NUMBA_CACHE)
def weakening_rate(static, dynamic, slip_distance):
    """(static - dynamic) / slip_distance, exactly 0 when the values are equal
    (infinite ones included) [unit of the parameter per m]."""
    if static == dynamic:
        return 0.0
    return (static - dynamic) / slip_distance


@njit(cache=NUMBA_CACHE)
def coulomb_return_map(
    gn,
    gt,
    slip_old,
    accumulated_old,
    pn0,
    kn,
    kt,
    friction,
    cohesion,
    friction_dynamic,
    cohesion_dynamic,
    slip_distance,
):
    """Return map of one contact point.

    Parameters
    ----------
    gn, gt : float, normal and tangential jump [m] (gn > 0 opens)
    slip_old : float, committed plastic slip g_T^p [m]
    accumulated_old : float, committed accumulated slip delta [m]
    pn0 : float, in-situ normal traction at zero jump [Pa] (<= 0)
    kn, kt : float, penalty stiffnesses [Pa/m]
    friction, cohesion : static f_s [-] and c_s [Pa]
    friction_dynamic, cohesion_dynamic : f_d [-] and c_d [Pa] (equal to the
        static ones for constant Coulomb friction)
    slip_distance : D_c [m] (> 0; inf for constant friction)

    Returns
    -------
    pn, pt : tractions [Pa]; state : OPEN | STICK | SLIP; slip_new : [m];
    accumulated_new : [m];
    d_nn, d_nt, d_tn, d_tt : consistent tangent d(pn, pt)/d(gn, gt) [Pa/m]
    """
    pn = kn * gn + pn0
    if pn > 0.0:
        return 0.0, 0.0, OPEN, gt, accumulated_old, 0.0, 0.0, 0.0, 0.0
    pt_trial = kt * (gt - slip_old)
    f = weakened(friction, friction_dynamic, accumulated_old, slip_distance)
    c = weakened(cohesion, cohesion_dynamic, accumulated_old, slip_distance)
    bound = c - f * pn
    if abs(pt_trial) <= bound:
        return pn, pt_trial, STICK, slip_old, accumulated_old, kn, 0.0, 0.0, kt
    sgn = 1.0 if pt_trial > 0.0 else -1.0
    trial = abs(pt_trial)
    rate_f = weakening_rate(friction, friction_dynamic, slip_distance)
    rate_c = weakening_rate(cohesion, cohesion_dynamic, slip_distance)
    if accumulated_old < slip_distance and (rate_f != 0.0 or rate_c != 0.0):
        H = rate_c - rate_f * pn  # softening of the bound per unit slip [Pa/m]
        if kt > H:
            dl = (trial - bound) / (kt - H)
            if dl <= slip_distance - accumulated_old:  # ends on the weakening branch
                f_new = f - rate_f * dl
                pt = sgn * (c - rate_c * dl - f_new * pn)
                # d|pt|/d|pt trial| = -H / (k_T - H); d|pt|/dpn = -f_new k_T / (k_T - H)
                scale = kt / (kt - H)
                return (
                    pn,
                    pt,
                    SLIP,
                    gt - pt / kt,
                    accumulated_old + dl,
                    kn,
                    0.0,
                    -sgn * f_new * kn * scale,
                    -H * scale,
                )
        # past the end of the weakening range (or k_T <= H): the dynamic bound
        bound = cohesion_dynamic - friction_dynamic * pn
        pt = sgn * bound
        return (
            pn,
            pt,
            SLIP,
            gt - pt / kt,
            accumulated_old + (trial - bound) / kt,
            kn,
            0.0,
            -sgn * friction_dynamic * kn,
            0.0,
        )
    pt = sgn * bound
    return (
        pn,
        pt,
        SLIP,
        gt - pt / kt,
        accumulated_old + (trial - bound) / kt,
        kn,
        0.0,
        -sgn * f * kn,
        0.0,
    )


@njit(cache=NUMBA_CACHE)
def contact_response(
    u,
    ip_dofs,
    ip_coef,
    ip_normal,
    ip_tangent,
    ip_weight,
    pn0,
    slip_old,
    accumulated_old,
    kn,
    kt,
    friction,
    cohesion,
    friction_dynamic,
    cohesion_dynamic,
    slip_distance,
    tangent_mode,
    pt_prev,
    gt_prev,
    out_f,
    out_K,
    out_gn,
    out_gt,
    out_pn,
    out_pt,
    out_state,
    out_slip,
    out_accumulated,
):
    """Contact forces and tangent of every interface point.

    The jump at point i is [[u]] = sum_k ip_coef[i, k] * (u[ip_dofs[i, 2k]],
    u[ip_dofs[i, 2k+1]]) over its J jumping enrichments (paper eq. 14 with
    the tip functions; dof -1 = absent).  The point's
    contribution to the internal force is w * coef_k * T with the traction
    T = p_N n + p_T t (eq. 20, f_int^con), its tangent w coef_k coef_l C with
    C = d T / d[[u]] (eq. 22 with the return-map tangent).

    Parameters
    ----------
    u : (n_dofs,) float64 [m]
    ip_dofs : (n, 2J) int64; ip_coef : (n, J) float64 [-]
    ip_normal, ip_tangent : (n, 2) float64; ip_weight : (n,) float64 [m]
    pn0 : (n,) [Pa]; slip_old, accumulated_old : (n,) [m]; kn, kt : (n,) [Pa/m];
    friction, friction_dynamic : (n,) [-]; cohesion, cohesion_dynamic : (n,) [Pa];
    slip_distance : (n,) [m] (coulomb_return_map)
    tangent_mode : TANGENT_CONSISTENT or TANGENT_SECANT (paper eq. 28; a
        point on a weakening branch keeps its consistent tangent: the
        secant of a softening branch has the wrong sign)
    pt_prev, gt_prev : (n,) p_T [Pa] and g_T [m] of the previous iteration
        (used by the secant tangent only)
    out_f : (n, 2J) [N/m]; out_K : (n, 2J, 2J) [N/m^2]; out_gn, out_gt : (n,) [m];
    out_pn, out_pt : (n,) [Pa]; out_state : (n,) int8; out_slip,
    out_accumulated : (n,) [m]
    """
    n_ip = ip_dofs.shape[0]
    J = ip_coef.shape[1]
    C = np.empty((2, 2))
    for i in range(n_ip):
        n0, n1 = ip_normal[i, 0], ip_normal[i, 1]
        t0, t1 = ip_tangent[i, 0], ip_tangent[i, 1]
        j0 = 0.0
        j1 = 0.0
        for k in range(J):
            dx = ip_dofs[i, 2 * k]
            dy = ip_dofs[i, 2 * k + 1]
            if dx >= 0:
                j0 += ip_coef[i, k] * u[dx]
            if dy >= 0:
                j1 += ip_coef[i, k] * u[dy]
        gn = j0 * n0 + j1 * n1
        gt = j0 * t0 + j1 * t1
        pn, pt, state, slip, acc, dnn, dnt, dtn, dtt = coulomb_return_map(
            gn,
            gt,
            slip_old[i],
            accumulated_old[i],
            pn0[i],
            kn[i],
            kt[i],
            friction[i],
            cohesion[i],
            friction_dynamic[i],
            cohesion_dynamic[i],
            slip_distance[i],
        )
        if tangent_mode == TANGENT_SECANT and state == SLIP and dtt == 0.0:
            # paper eq. 28: k_T = (p_T^{n+1} - p_T^n) / |Delta w_T|, no n-t coupling
            dg = abs(gt - gt_prev[i])
            dtt = kt[i] if dg <= SECANT_MIN_INCREMENT else abs(pt - pt_prev[i]) / dg
            dtt = min(dtt, kt[i])
            dtn = 0.0
        out_gn[i] = gn
        out_gt[i] = gt
        out_pn[i] = pn
        out_pt[i] = pt
        out_state[i] = state
        out_slip[i] = slip
        out_accumulated[i] = acc
        T0 = pn * n0 + pt * t0
        T1 = pn * n1 + pt * t1
        # C = n (dnn n + dnt t)^T + t (dtn n + dtt t)^T
        C[0, 0] = n0 * (dnn * n0 + dnt * t0) + t0 * (dtn * n0 + dtt * t0)
        C[0, 1] = n0 * (dnn * n1 + dnt * t1) + t0 * (dtn * n1 + dtt * t1)
        C[1, 0] = n1 * (dnn * n0 + dnt * t0) + t1 * (dtn * n0 + dtt * t0)
        C[1, 1] = n1 * (dnn * n1 + dnt * t1) + t1 * (dtn * n1 + dtt * t1)
        w = ip_weight[i]
        for k in range(J):
            ck = w * ip_coef[i, k]
            out_f[i, 2 * k] = ck * T0
            out_f[i, 2 * k + 1] = ck * T1
            for m in range(J):
                ckm = ck * ip_coef[i, m]
                out_K[i, 2 * k, 2 * m] = ckm * C[0, 0]
                out_K[i, 2 * k, 2 * m + 1] = ckm * C[0, 1]
                out_K[i, 2 * k + 1, 2 * m] = ckm * C[1, 0]
                out_K[i, 2 * k + 1, 2 * m + 1] = ckm * C[1, 1]
