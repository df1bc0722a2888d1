"""Frictional contact on the fractures: the interface operators and history, the
predictor of a load step's stick/slip set, and the local branch search.

Modules:

- ``interface``: ``ContactSet``: interface-point operators, history and the
  kernel call;
- ``predictor``: a first guess of the stick/slip set of a load step;
- ``branches``: a consistent stick/slip set for a small cluster of contact
  patches;
- ``defaults``: the automatic penalty, its measured range and the patch
  length (the case reader's defaults).

The subpackage imports nothing itself: import the module you need (``from
xfemslip.contact.interface import ...``)."""

__all__ = ["branches", "defaults", "interface", "predictor"]
