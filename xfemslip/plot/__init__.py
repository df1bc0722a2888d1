"""Figures (matplotlib, imported only when a figure is drawn) and the data they
read from a run's output files.

Modules:

- ``data``: what the figures need from a run, read through
  :func:`xfemslip.io.read.read_result`;
- ``figures``: the figures of ``xfemslip plot``;
- ``mohr``: the Mohr-Coulomb diagram;
- ``depletion``: the figures of ``xfemslip deplete``;
- ``dfn``: figures of fracture networks.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.plot.data import ...``)."""

__all__ = ["data", "depletion", "dfn", "figures", "mohr"]
