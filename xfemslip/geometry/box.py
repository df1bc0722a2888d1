"""The axis-aligned box [x0, x1] x [y0, y1] [m]: the domain, a reservoir or
refinement box, the permeability block, a network's region.

``Box`` is a named tuple in the order (x0, x1, y0, y1), the order of the
mesh's cell bounds (``Mesh.bounds``) and of the clipping routines
(``fracture.clip_segment``, ``dfn.clip_to_box``), so it goes wherever they
take a box.  The other forms in which a box arrives or leaves are converted
here and nowhere else:

- ``from_corners(x0, y0, x1, y1)`` / ``corners``: the case file's and
  ``result.h5``'s order (``box``, ``boxes``, ``refine``, ``block``);
- ``from_origin_size(origin, size)``: ``[domain]`` (the width and height
  stay the case's own numbers: x1 - x0 may differ from them in the last
  bit);
- ``from_lines(x, y)``: a rectilinear mesh's grid lines (the domain of a
  built mesh);
- ``lo``, ``hi``: the lower-left and upper-right corners;
- ``vertices()``: the box as a polygon.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

__all__ = ["Box"]


class Box(NamedTuple):
    """An axis-aligned box [x0, x1] x [y0, y1] [m]."""

    x0: float
    x1: float
    y0: float
    y1: float

    @classmethod
    def from_corners(cls, x0: float, y0: float, x1: float, y1: float) -> Box:
        """From the lower-left and upper-right corners, in the case file's
        order [x0, y0, x1, y1]."""
        return cls(float(x0), float(x1), float(y0), float(y1))

    @classmethod
    def from_origin_size(cls, origin: Sequence[float], size: Sequence[float]) -> Box:
        """From the lower-left corner and the width and height (``[domain]``)."""
        x0, y0 = float(origin[0]), float(origin[1])
        return cls(x0, x0 + float(size[0]), y0, y0 + float(size[1]))

    @classmethod
    def from_lines(cls, x: np.ndarray, y: np.ndarray) -> Box:
        """The box a rectilinear mesh with increasing grid lines x, y covers."""
        return cls(float(x[0]), float(x[-1]), float(y[0]), float(y[-1]))

    @property
    def corners(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1): the case file's and result.h5's order."""
        return (self.x0, self.y0, self.x1, self.y1)

    @property
    def width(self) -> float:
        return self.x1 - self.x0

    @property
    def height(self) -> float:
        return self.y1 - self.y0

    @property
    def area(self) -> float:
        return self.width * self.height

    @property
    def lo(self) -> tuple[float, float]:
        """The lower-left corner (x0, y0) [m]."""
        return (self.x0, self.y0)

    @property
    def hi(self) -> tuple[float, float]:
        """The upper-right corner (x1, y1) [m]."""
        return (self.x1, self.y1)

    def vertices(self) -> np.ndarray:
        """(4, 2) corners counter-clockwise from the lower-left one [m]."""
        return np.array(
            [
                [self.x0, self.y0],
                [self.x1, self.y0],
                [self.x1, self.y1],
                [self.x0, self.y1],
            ]
        )

    def contains(self, xy: np.ndarray) -> np.ndarray:
        """(n,) bool: points (n, 2) strictly inside the box."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        x, y = xy[:, 0], xy[:, 1]
        return (x > self.x0) & (x < self.x1) & (y > self.y0) & (y < self.y1)
