"""Numbers as the terminal shows them: engineering units, a stated sign
convention, and aligned tables.

The files (``result.h5``, the CSV tables) keep SI and tension positive
(:mod:`xfemslip.conventions`); what ``check``, ``deplete``, ``screen`` and
``summary`` print goes through here: stresses and pressures in MPa, moduli
in GPa, gradients in MPa/km, lengths in m (km from 10 km), displacements and
slip in mm.  With ``compression_positive`` a stress or a traction is printed
with its sign turned (compression > 0), and a pore-pressure change as a
depletion (a drop > 0); a pressure is a pressure in both conventions.

>>> stress(-13.7109e6), stress(-13.7109e6, compression_positive=True)
('-13.7109 MPa', '13.7109 MPa')
>>> modulus(2.0e10), gradient(-23.0e3), length(3500.0), slip(1.5e-4)
('20 GPa', '-23 MPa/km', '3500 m', '0.15 mm')
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

__all__ = [
    "change_label",
    "convention",
    "gradient",
    "length",
    "megapascals",
    "modulus",
    "pressure",
    "pressure_change",
    "slip",
    "stress",
    "table",
]

DIGITS = 6  # significant digits of a printed number (what a case file types)


def number(value: float, digits: int = DIGITS) -> str:
    """``value`` to ``digits`` significant digits, without ``-0``."""
    text = f"{float(value):.{digits}g}"
    return "0" if text == "-0" else text


def megapascals(value: float, compression_positive: bool = False) -> float:
    """A stress or traction [Pa] in MPa, in the chosen sign convention."""
    return (-value if compression_positive else value) / 1e6


def stress(value: float, compression_positive: bool = False) -> str:
    """A stress or traction [Pa]: ``-13.7109 MPa`` (tension positive)."""
    return f"{number(megapascals(value, compression_positive))} MPa"


def pressure(value: float) -> str:
    """A pore or fluid pressure [Pa]: ``30 MPa`` (a pressure in either
    convention)."""
    return f"{number(value / 1e6)} MPa"


def pressure_change(value: float, compression_positive: bool = False) -> str:
    """A pore-pressure change [Pa]: ``-25 MPa`` (< 0 = depletion), or with
    ``compression_positive`` the depletion ``25 MPa``."""
    return f"{number(megapascals(value, compression_positive))} MPa"


def change_label(compression_positive: bool = False) -> str:
    """The name of a pore-pressure change column: dp or depletion."""
    return "depletion" if compression_positive else "dp"


def modulus(value: float) -> str:
    """An elastic modulus [Pa]: ``20 GPa``."""
    return f"{number(value / 1e9)} GPa"


def gradient(value: float, compression_positive: bool = False) -> str:
    """A stress gradient with depth [Pa/m]: ``-23 MPa/km``."""
    return f"{number(megapascals(value, compression_positive) * 1e3)} MPa/km"


def length(value: float) -> str:
    """A length or coordinate [m]: ``3500 m``, ``12.5 km`` from 10 km."""
    if abs(value) >= 1e4:
        return f"{number(value / 1e3)} km"
    return f"{number(value)} m"


def slip(value: float) -> str:
    """A displacement, slip or opening [m]: ``0.15 mm``."""
    return f"{number(value * 1e3)} mm"


def convention(compression_positive: bool = False) -> str:
    """The sentence that says how signs are printed."""
    if compression_positive:
        return (
            "signs: compression positive (stresses and tractions; a pore-pressure "
            "change is printed as the depletion, a drop > 0)"
        )
    return (
        "signs: tension positive (stresses and tractions; a pore-pressure change "
        "dp < 0 is a depletion)"
    )


def table(
    headers: Sequence[str],
    rows: Sequence[Sequence[str]],
    left: Collection[int] = (),
) -> str:
    """Rows of text cells under their headers, two spaces apart, no trailing
    blanks; columns right-aligned, those whose index is in ``left``
    left-aligned."""
    import io

    from rich.console import Console
    from rich.table import Table
    from rich.text import Text  # plain text: "[MPa]" is not a style tag

    grid = Table(box=None, pad_edge=False, show_edge=False, header_style="")
    for k, head in enumerate(headers):
        if k in left:
            grid.add_column(Text(head), justify="left", no_wrap=True)
        else:
            grid.add_column(Text(head), justify="right", no_wrap=True)
    for row in rows:
        grid.add_row(*(Text(cell) for cell in row))
    out = io.StringIO()
    console = Console(
        file=out, width=10_000, color_system=None, highlight=False, soft_wrap=True
    )
    console.print(grid)
    return "\n".join(line.rstrip() for line in out.getvalue().splitlines())
