"""Fracture and reservoir geometry on the domain, pure NumPy.

Modules:

- ``box``: ``Box``, the axis-aligned box (the domain, a region's boxes, the
  permeability block) and its conversions from and to the case file's forms;
- ``fracture``: one Fracture (a polyline clipped to the domain and brought
  to the mesh's resolution), level sets, cell pieces, tips; ``build_fracture``;
- ``junctions``: where fractures meet (X, T/Y, V), the snapping of ends onto
  nearby fractures, the cuts of each arm's Heaviside; ``build_fractures``,
  all fractures of a case;
- ``polyline``: polyline simplification and the first self-meeting of a
  polyline or polygon;
- ``regions``: reservoir regions (boxes or a polygon) and which cells they
  hold;
- ``dfn``: random discrete fracture networks from a seeded generator, their
  statistics and CSV text.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.geometry.fracture import ...``)."""

__all__ = ["box", "dfn", "fracture", "junctions", "polyline", "regions"]
