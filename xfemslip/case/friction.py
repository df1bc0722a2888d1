"""``friction`` and ``cohesion`` of a fracture (``[[fractures]]``, ``[network]``):
a number, constant Coulomb friction as in version 1, or a slip-weakening law::

    friction = { law = "slip_weakening", static = 0.6, dynamic = 0.45,
                 slip_distance = 0.005 }
    cohesion = { static = 2.0e6, dynamic = 0.0 }   # optional, same distance

Friction falls linearly from ``static`` to ``dynamic`` over ``slip_distance``
metres of accumulated slip (kernels.contact).  A number ``cohesion`` with a
slip-weakening friction stays constant; a table ``cohesion`` weakens with the
friction and needs it (it has no slip distance of its own).  The spec keeps
the static values in ``FractureSpec.friction`` and ``cohesion`` (what first
slip, screening and the in-situ margin use) and the rest in
``FractureSpec.weakening``.
"""

from __future__ import annotations

from xfemslip import display
from xfemslip.case.specs import SlipWeakeningSpec
from xfemslip.case.tables import (
    NON_NEGATIVE,
    POSITIVE,
    REQUIRED,
    Table,
    exact,
    fmt,
    show,
)

__all__ = [
    "COHESION_LAW_KEYS",
    "FRICTION_LAWS",
    "FRICTION_LAW_KEYS",
    "Strength",
    "describe_strength",
    "read_strength",
]

FRICTION_LAWS = ("slip_weakening",)
FRICTION_LAW_KEYS = ("law", "static", "dynamic", "slip_distance")
COHESION_LAW_KEYS = ("static", "dynamic")


class Strength:
    """What a table gives of friction and cohesion.

    friction, cohesion : the static values (None where the table leaves the
        key out and it has no default);
    dynamic_friction, slip_distance : of a slip-weakening friction (None for
        a number);
    dynamic_cohesion : of a table cohesion (None for a number);
    ok : False when a problem was recorded.
    """

    def __init__(self, friction, cohesion, dynamic_friction, slip_distance,
                 dynamic_cohesion, ok):  # fmt: skip
        self.friction = friction
        self.cohesion = cohesion
        self.dynamic_friction = dynamic_friction
        self.slip_distance = slip_distance
        self.dynamic_cohesion = dynamic_cohesion
        self.ok = ok

    @property
    def weakens(self) -> bool:
        """Whether the friction is a slip-weakening law."""
        return self.slip_distance is not None

    def weakening(self, friction=None, cohesion=None) -> SlipWeakeningSpec | None:
        """The SlipWeakeningSpec of a fracture that takes this law, or None
        for constant friction.  ``friction`` / ``cohesion``: a number given
        for the fracture itself (a [network] CSV column), which replaces the
        law's static and dynamic values of that parameter."""
        if not self.weakens:
            return None
        if cohesion is not None:
            dynamic_cohesion = cohesion
        elif self.dynamic_cohesion is not None:
            dynamic_cohesion = self.dynamic_cohesion
        else:
            dynamic_cohesion = self.cohesion if self.cohesion is not None else 0.0
        return SlipWeakeningSpec(
            dynamic_friction=self.dynamic_friction if friction is None else friction,
            dynamic_cohesion=dynamic_cohesion,
            slip_distance=self.slip_distance,
        )


def _static_dynamic(sub: Table, name: str) -> tuple[float | None, float | None]:
    """``static`` and ``dynamic`` of a law table: both >= 0, dynamic <= static."""
    static = sub.number("static", rule=NON_NEGATIVE)
    dynamic = sub.number("dynamic", rule=NON_NEGATIVE)
    if static is not None and dynamic is not None and dynamic > static:
        sub.error(
            "dynamic",
            f"must be <= static = {fmt(static)} (the {name} weakens with slip), "
            f"got {exact(dynamic)}",
        )
        dynamic = None
    return static, dynamic


def _neither(table: Table, name: str) -> bool:
    """Whether ``name`` is given as something other than a number or a table."""
    if not table.has(name):
        return False
    value = table.data[name]
    number = isinstance(value, int | float) and not isinstance(value, bool)
    return not (number or isinstance(value, dict))


def read_strength(table: Table, friction_default=REQUIRED, cohesion_default=0.0):
    """``friction`` and ``cohesion`` of ``table`` (a fracture or [network])
    -> Strength; problems are recorded in the table's list."""
    start = len(table.problems)
    dynamic_friction = slip_distance = dynamic_cohesion = None
    if isinstance(table.data.get("friction"), dict):
        sub = table.table("friction", FRICTION_LAW_KEYS)
        assert sub is not None  # a table (checked above)
        sub.choice("law", FRICTION_LAWS)
        friction, dynamic_friction = _static_dynamic(sub, "friction")
        slip_distance = sub.number("slip_distance", rule=POSITIVE)
    elif _neither(table, "friction"):
        table.error(
            "friction",
            "expected a number (constant friction) or a table { law = "
            f'"slip_weakening", static, dynamic, slip_distance }}, got '
            f"{show(table.data['friction'])}",
        )
        friction = None
    else:
        friction = table.number("friction", friction_default, rule=NON_NEGATIVE)
    if isinstance(table.data.get("cohesion"), dict):
        sub = table.table("cohesion", COHESION_LAW_KEYS)
        assert sub is not None  # a table (checked above)
        cohesion, dynamic_cohesion = _static_dynamic(sub, "cohesion")
        if not isinstance(table.data.get("friction"), dict):
            table.error(
                "cohesion",
                "a weakening cohesion { static, dynamic } needs friction = "
                '{ law = "slip_weakening", ... }: it weakens over that '
                "slip_distance",
            )
    elif _neither(table, "cohesion"):
        table.error(
            "cohesion",
            "expected a number (Pa) or a table { static, dynamic }, got "
            f"{show(table.data['cohesion'])}",
        )
        cohesion = None
    else:
        cohesion = table.number("cohesion", cohesion_default, rule=NON_NEGATIVE)
    return Strength(
        friction,
        cohesion,
        dynamic_friction,
        slip_distance,
        dynamic_cohesion,
        ok=len(table.problems) == start,
    )


def describe_strength(friction, cohesion, weakening) -> tuple[str, str]:
    """(friction, cohesion) as ``xfemslip check`` prints them."""
    if weakening is None:
        return fmt(friction), display.pressure(cohesion)
    over = f"over {display.slip(weakening.slip_distance)} of slip"
    f_text = f"slip weakening {fmt(friction)} -> {fmt(weakening.dynamic_friction)}"
    if weakening.dynamic_cohesion == cohesion:
        return f"{f_text} {over}", display.pressure(cohesion)
    c_text = (
        f"{display.number(cohesion / 1e6)} -> "
        f"{display.pressure(weakening.dynamic_cohesion)} {over}"
    )
    return f"{f_text} {over}", c_text
