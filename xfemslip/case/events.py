"""``[events]``: how the size of a slip event is reported.

A 2D model has no out-of-plane extent, so a moment magnitude needs one:
``extent`` W [m] is the user's assumption of it.  Without the table (or the
key), each fracture's magnitude uses W = its own slipping length, and every
printed magnitude says which W it used.
"""

from __future__ import annotations

from xfemslip.case.specs import EventsSpec
from xfemslip.case.tables import Range, Table

__all__ = ["EVENTS_KEYS", "EXTENT", "read_events"]

EVENTS_KEYS = ("extent",)
# W from a millimetre (a laboratory slip patch) to 10,000 km (beyond the
# longest ruptures on Earth); M0' W then stays a normal number.
EXTENT = Range(1e-3, 1e7)


def read_events(root: Table) -> EventsSpec | None:
    """[events]: ``extent`` in EXTENT [m] (optional); None without the table."""
    table = root.table("events", EVENTS_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    extent = table.number("extent", None, EXTENT)
    if len(table.problems) > start:
        return None
    return EventsSpec(extent=extent)
