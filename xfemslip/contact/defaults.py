"""The contact law's numerical defaults: the automatic penalty stiffness, the
penalty range where Newton was measured to converge, and the contact patch
length.  The solver and the contact driver use them; the case reader
(xfemslip.case) takes its defaults and its warnings from here.
"""

from __future__ import annotations

__all__ = [
    "AUTO_PENALTY",
    "CONTACT_PATCH_CELLS",
    "PENALTY_RATIO_LOWEST",
    "PENALTY_RATIO_MEASURED",
]

# Penalty stiffness when a fracture omits kn / kt: k = AUTO_PENALTY * E / h with
# h the local cell size (sqrt of the area of the cut cell).  Measured on the
# inclined crack (docs/case-format.md, "Automatic penalty"): below ~1e3 the stuck faces'
# elastic penalty slip is the larger error (2e-4 of the free slip at 100, 3e-2
# at 1), from 1e3 up it sits at the discretisation floor (5e-5); the slip error
# (0.42 % at a/20) and the Newton iterations (2 per step on the plate case up
# to 1e5) do not change.  A stiffer penalty only worsens the conditioning.
AUTO_PENALTY = 1.0e3
# The penalty range kn h/E where Newton was measured to converge on every
# shipped case, kn = kt = 10^k E/h for k = -1..9 (benchmarks/penalty_range.py,
# docs/robustness.md "Known limits"): 0.1 to 1e6.  Above it the contact
# stiffness swamps the bulk stiffness by that ratio and the residual stalls at
# round-off (eta 1e-8 to 6e-8, stick/slip states settled), just above the
# default tolerance; every Newton failure then names the penalty and the top
# of the range, and `check` and `run` warn outside it.
PENALTY_RATIO_MEASURED = 1.0e6
PENALTY_RATIO_LOWEST = 0.1

# Length of a contact patch in local cell sizes ([solver] contact_patch): the
# penalty law acts on the jump averaged over each patch (contact.ContactSet).
# Measured on the inclined crack at h = a/20: normal-traction oscillation (max
# deviation / mean) 23 % pointwise (0), 1.2 % with 1-cell patches, 0.3 % with
# 1.5-cell patches, slip error unchanged (docs/verification.md, "Contact
# tractions: patches against points").
CONTACT_PATCH_CELLS = 1.5
