"""What the results are checked against, in closed form (pure NumPy, no
model): the frictional straight crack, the slip window, depletion of a
reservoir, the Coulomb screening of orientations, and the OpenGeoSys peer
problem as an xfemslip case.

Modules:

- ``closed_form``: the frictional straight crack and the slip window;
- ``closed_form_depletion``: uniaxial strain and the offset-reservoir fault
  under depletion;
- ``inclusion``: the stress of a pressure change in polygons of an infinite
  plane (Goodier's potential in closed form) and the displaced fault of
  Jansen, Singhal & Vossepoel (2019);
- ``onset``: the pore-pressure change at which a plane first slips or opens
  along a linear stress path (the one law of the screens and closed forms);
- ``screen``: closed-form screening of fracture orientations (Coulomb margin
  of each plane);
- ``peer``: the OpenGeoSys peer problem as an xfemslip case.

Nothing here imports the solver, so the case checks, post-processing and
figures may use these formulas.  The subpackage imports nothing itself:
import the module you need (``from xfemslip.reference.closed_form import
...``).
"""

__all__ = [
    "closed_form",
    "closed_form_depletion",
    "inclusion",
    "onset",
    "peer",
    "screen",
]
