"""Tests of xfemslip.contact.interface: contact patches, their jump operators, the
automatic penalty."""

from __future__ import annotations

import numpy as np
import pytest

from xfemslip.case import build, loads_case
from xfemslip.contact.defaults import AUTO_PENALTY
from xfemslip.contact.interface import _point_jumps, contact_patches
from xfemslip.simulation import build_model


def _model(patch=1.5, penalty=None, graded=False):
    """The case on a 20 x 16 grid (x graded near the fracture's kink), with
    the penalties ``penalty`` (default kn = 1e13, kt = 2e13 Pa/m; {} for the
    automatic ones) and contact patches of ``patch`` cells."""
    if penalty is None:
        penalty = {"kn": 1.0e13, "kt": 2.0e13}
    x = np.linspace(0.0, 1.0, 21)
    if graded:
        x = np.sort(np.concatenate([x, [0.625, 0.675, 0.725, 0.775]]))
    fracture = {
        "points": [[0.13, 0.21], [0.52, 0.47], [0.83, 0.58]],
        "friction": 0.3,
        **penalty,
    }
    text = build.case_text(
        {
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"x": x, "y": np.linspace(0.0, 1.0, 17)},
            "material": {"E": 1.0e10, "nu": 0.25, "model": "plane_strain"},
            "fractures": [fracture],
            "loading": {"stress": {"xx": -1.0e6, "yy": -2.0e6, "xy": 0.0}},
            "boundary": {
                "bottom": {"uy": 0.0},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
            "solver": {"contact_patch": patch},
        }
    )
    return build_model(loads_case(text))


def _cell_size(m):
    b = m.mesh.bounds[m.ip.cell]
    return np.sqrt((b[:, 1] - b[:, 0]) * (b[:, 3] - b[:, 2]))


@pytest.mark.parametrize("graded", [False, True])
@pytest.mark.parametrize("cells", [0.5, 1.0, 1.5, 3.0])
def test_patches_tile_each_segment_in_runs_of_the_asked_length(cells, graded):
    m = _model(cells, graded=graded)
    ip, fr = m.ip, m.fractures[0]
    patch = contact_patches(m.mesh, m.fractures, ip, cells)
    ends = np.cumsum(fr.length)
    seg = np.searchsorted(ends, ip.s, side="right")
    size = _cell_size(m)
    for p in np.unique(patch):
        mine = patch == p
        # a patch is a contiguous run of arc length on one straight segment
        assert np.unique(seg[mine]).size == 1
        others = ip.s[~mine & (seg == seg[mine][0])]
        lo, hi = ip.s[mine].min(), ip.s[mine].max()
        assert not np.any((others > lo) & (others < hi))
        # ... at least `cells` local cell sizes long, unless it is the whole segment
        length_in_cells = np.sum(ip.weight[mine] / size[mine])
        whole_segment = np.all(seg[patch == p][0] != seg[~mine])
        assert length_in_cells >= cells - 1e-9 or whole_segment
        # ... and short of twice that plus one cell (the greedy rule's bound)
        assert length_in_cells < 2 * cells + 2.0
    # weights of the patches add up to the fracture length
    np.testing.assert_allclose(m.contact.weight.sum(), fr.length.sum(), rtol=1e-12)


def test_zero_patch_length_is_pointwise():
    m = _model(0.0)
    assert m.contact.weight.size == m.ip.n
    np.testing.assert_array_equal(m.contact.patch, np.arange(m.ip.n))


def test_patch_jump_is_the_weighted_mean_of_the_point_jumps():
    """[[u]]_P = sum_p w_p [[u]]_p / W_P for a random u (an independent sum)."""
    m = _model(1.5)
    c = m.contact
    u = np.random.default_rng(3).normal(size=m.problem.n_dofs)
    point = _point_jumps(u, c.point_dofs, c.point_coef)
    W = np.bincount(c.patch, weights=m.ip.weight)
    mean = np.column_stack(
        [np.bincount(c.patch, weights=m.ip.weight * point[:, k]) / W for k in (0, 1)]
    )
    np.testing.assert_allclose(
        _point_jumps(u, c.dofs, c.coef), mean, rtol=1e-12, atol=1e-14
    )
    res = c.evaluate(u, 0, c.pt_committed, c.gt_committed)
    # reported point values: own jump, the patch's traction and state
    np.testing.assert_allclose(res.point_gt, np.einsum("nk,nk->n", point, m.ip.tangent))
    np.testing.assert_array_equal(res.point_pn, res.pn[c.patch])
    np.testing.assert_array_equal(res.point_state, res.state[c.patch])


def test_omitted_penalty_is_automatic_from_E_and_the_local_cell_size():
    m = _model(1.5, penalty={}, graded=True)
    c = m.contact
    W = np.bincount(c.patch, weights=m.ip.weight)
    h = np.bincount(c.patch, weights=m.ip.weight * _cell_size(m)) / W
    np.testing.assert_allclose(c.kn, AUTO_PENALTY * 1.0e10 / h, rtol=1e-12)
    np.testing.assert_allclose(c.kt, c.kn)
    assert c.kn.max() > 1.2 * c.kn.min()  # graded: finer cells, stiffer penalty
    # a given kn is used as given
    m2 = _model(1.5, penalty={"kn": 3.0e13}, graded=True)
    np.testing.assert_allclose(m2.contact.kn, 3.0e13)
    np.testing.assert_allclose(m2.contact.kt, c.kt)
