"""The conventions every part of xfemslip shares: signs, contact states, tangents.

This module is the one definition of these facts; the kernels, the Newton
solver, the output writers, the readers and the figures import them from here.

Signs (``output-format.md``, *Sign conventions*):

- SI units everywhere: m, Pa, N per metre of thickness; penalty stiffnesses in
  Pa/m.  Angles in case files are degrees, converted once by :mod:`xfemslip.case`.
- Stress and traction are **tension positive**; a compressive normal traction
  is negative.
- ``t`` is the unit tangent of a fracture segment, from its first point to its
  last; ``n = (-t_y, t_x)`` is ``t`` turned 90 degrees counter-clockwise.  The
  ``+`` side is the side ``n`` points to and the jump is ``[[u]] = u(+) - u(-)``.
- Opening ``g_N = [[u]] . n`` (positive opens, negative is penalty
  interpenetration); slip ``g_T = [[u]] . t``.
- Normal traction ``p_N = n . sigma . n`` (<= 0 in contact), shear traction
  ``p_T = t . sigma . n``.  Coulomb: ``|p_T| <= c - f p_N`` on a closed face.

Contact states: the ``state`` of a contact point, as the kernels return it and
as ``result.h5`` stores it (``/fractures/<i>/state``, int8).  ``SLIP_BACKWARD``
is never stored: it is the branch of a point slipping against ``t`` (p_T < 0),
which the Newton solver tells apart from slipping along ``t`` because a switch
between the two changes the tangent.
"""

from __future__ import annotations

OPEN = 0
STICK = 1
SLIP = 2
SLIP_BACKWARD = 3

# The text of the state codes in result.h5 (root attribute ``status_codes``
# and the ``codes`` attribute of every ``state`` dataset).
STATE_CODES = "0 open, 1 stick, 2 slip"

# Tangent of the contact law ([solver] tangent): the exact derivative of the
# return map, or the secant update of the paper's eq. 28.
TANGENT_CONSISTENT = 0
TANGENT_SECANT = 1
TANGENTS = {"consistent": TANGENT_CONSISTENT, "secant": TANGENT_SECANT}

__all__ = [
    "OPEN",
    "SLIP",
    "SLIP_BACKWARD",
    "STATE_CODES",
    "STICK",
    "TANGENTS",
    "TANGENT_CONSISTENT",
    "TANGENT_SECANT",
]
