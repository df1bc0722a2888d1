"""Plausibility warnings: a valid case whose values look like a mistake.

These never refuse a case (the values are legal, and a user may mean them);
``check``, ``run`` and ``deplete`` log each as a WARNING line naming the key,
the value and why it looks wrong:

- a Young's modulus outside what rock and the materials around it have
  (E_RANGE: a value in GPa or MPa written as Pa);
- a far-field stress that compresses nothing, with fractures in the case
  (the faces open instead of slipping; the paper's problems are in
  compression, signs in docs/output-format.md: compression negative);
- a penalty stiffness kn h/E or kt h/E outside the range where Newton was
  measured to converge (xfemslip.contact.defaults: PENALTY_RATIO_LOWEST to
  PENALTY_RATIO_MEASURED);
- a fracture that reaches outside the domain (it is clipped at the boundary,
  so its tip there becomes an edge crossing);
- a unit's edge that was moved onto a fracture it lay within 0.1 cell of
  (xfemslip.case.units.snap_to_fractures).
"""

from __future__ import annotations

import numpy as np

from xfemslip.case.specs import CaseSpec
from xfemslip.contact.defaults import PENALTY_RATIO_LOWEST, PENALTY_RATIO_MEASURED

__all__ = ["E_RANGE", "plausibility_warnings"]

# Young's moduli of rocks and the materials a model puts around them: soft
# shales and chalk about 0.1 GPa up to steel at 210 GPa [Pa]; 1 MPa is clay
# paste, 1e12 Pa stiffer than diamond.
E_RANGE = (1.0e6, 1.0e12)


def plausibility_warnings(spec: CaseSpec) -> list[str]:
    """The warnings of a validated ``CaseSpec``, one line each."""
    out: list[str] = []
    moduli = [("material.E", spec.material.E)]
    if spec.reservoir is not None:
        moduli.append(("reservoir.E", spec.reservoir.E))
    else:
        moduli += [(f"units[{i}].E", u.E) for i, u in enumerate(spec.units)]
    for key, E in moduli:
        if not E_RANGE[0] <= E <= E_RANGE[1]:
            out.append(
                f"{key} = {E:g} Pa lies outside {E_RANGE[0]:g} to {E_RANGE[1]:g} "
                "Pa, the moduli of rocks (in Pa: 5 GPa is 5e9)"
            )
    stress = spec.loading.stress
    if spec.fractures and stress is not None and any(stress):
        sxx, syy, sxy = stress
        smin = 0.5 * (sxx + syy) - np.hypot(0.5 * (sxx - syy), sxy)
        if smin >= 0.0:
            out.append(
                f"loading.stress = {list(stress)} Pa compresses nothing "
                "(compression is negative): the fractures open rather than slip"
            )
    h = float(min(np.diff(spec.mesh.x).min(), np.diff(spec.mesh.y).min()))
    E = min(E for _, E in moduli)
    for fr in spec.fractures:
        for name in ("kn", "kt"):
            k = getattr(fr, name)
            if k is None:
                continue
            ratio = k * h / E
            if not PENALTY_RATIO_LOWEST <= ratio <= PENALTY_RATIO_MEASURED:
                out.append(
                    f"{_where(fr)}.{name} = {k:g} Pa/m gives {name}*h/E = "
                    f"{ratio:.3g}, outside {PENALTY_RATIO_LOWEST:g} to "
                    f"{PENALTY_RATIO_MEASURED:g} where Newton was measured to "
                    f"converge (e.g. {1e3 * E / h:.3g} Pa/m, or leave it out)"
                )
    for i, unit in enumerate(spec.units):
        key = "reservoir" if spec.reservoir is not None else f"units[{i}]"
        for edge, fracture, distance in unit.snapped:
            out.append(
                f"{key}: {edge} lies {distance:.3g} m off fractures[{fracture}] "
                "and is moved onto it (within 0.1 cell of a fracture, an edge is "
                "taken to follow it)"
            )
    x0, x1, y0, y1 = spec.box
    tol = 1e-9 * max(spec.size)
    for fr in spec.fractures:
        p = fr.points
        outside = (
            (p[:, 0] < x0 - tol)
            | (p[:, 0] > x1 + tol)
            | (p[:, 1] < y0 - tol)
            | (p[:, 1] > y1 + tol)
        )
        if outside.any():
            out.append(
                f"{_where(fr)} reaches outside the domain and is clipped at its "
                "boundary (the end there is no crack tip)"
            )
    return out


def _where(fr) -> str:
    """The key of a fracture: ``fractures[i]``, or its [network] source."""
    return f"fractures[{fr.index}]" if not fr.source else fr.source
