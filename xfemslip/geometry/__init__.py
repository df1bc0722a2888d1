"""Fracture and reservoir geometry on the domain, pure NumPy.

Modules:

- ``fracture``: Fracture (polylines clipped to the domain), level sets, cell
  pieces, tips and junctions; ``build_fractures``;
- ``polyline``: polyline simplification and the first self-meeting of a
  polyline or polygon;
- ``regions``: reservoir regions (boxes or a polygon) and which cells they
  hold;
- ``dfn``: random discrete fracture networks from a seeded generator, their
  statistics and CSV text.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.geometry.fracture import ...``)."""

__all__ = ["dfn", "fracture", "polyline", "regions"]
