"""Mesh.nodes_within: the nodes at most a radius from a point, found on
the grid lines' box around it, are those a test of every node finds."""

from __future__ import annotations

import numpy as np
import pytest

from xfemslip.fem.mesh import build_mesh


def _graded(rng) -> tuple[np.ndarray, np.ndarray]:
    """Grid lines of a graded mesh: cell sizes spread over a factor 30."""
    dx = np.exp(rng.uniform(0.0, np.log(30.0), 41))
    dy = np.exp(rng.uniform(0.0, np.log(30.0), 29))
    x = np.concatenate([[0.0], np.cumsum(dx)]) / dx.sum() * 2.0 - 0.5
    y = np.concatenate([[0.0], np.cumsum(dy)]) / dy.sum() * 1.5 + 0.25
    return x, y


@pytest.mark.parametrize("seed", range(5))
def test_nodes_within_is_the_test_of_every_node(seed):
    rng = np.random.default_rng(seed)
    mesh = build_mesh(*_graded(rng))
    points = np.vstack(
        [
            rng.uniform([-0.8, 0.0], [1.8, 2.0], size=(40, 2)),  # some outside
            mesh.nodes[rng.integers(0, mesh.n_nodes, 10)],  # on nodes
        ]
    )
    for p in points:
        dist = np.linalg.norm(mesh.nodes - p, axis=1)
        # radii of all sizes, and exactly the distance of some node
        radii = [*rng.uniform(0.0, 0.6, 4), *rng.choice(dist, 3), 0.0, 5.0]
        for r in radii:
            expected = np.nonzero(dist <= r)[0]
            np.testing.assert_array_equal(mesh.nodes_within(p, r), expected)
