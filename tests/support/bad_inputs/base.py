"""Shared pieces of the generated bad-input suite (``bad_inputs.py``): the
``Input`` record, special files, the base cases the generators mutate.

Each ``Input`` is a folder of files (case, sweep, CSV files, special files), a
command line, an environment, and what may come out: the allowed exit codes
(0 run, 1 clean failure, 2 refusal) and, where the input breaks one key, the
text the refusal must name (the key, the option, the variable, the file).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path

import tomli_w

REPO = Path(__file__).resolve().parents[3]
CASES = REPO / "cases"
SHIPPED = sorted(CASES.glob("*.toml"))

RUN = ("run", "-q")
OUT = "out"


@dataclass(frozen=True)
class Special:
    """A file that is not plain bytes: ``kind`` in fifo, dir, symlink (to
    ``arg``), sparse (of ``arg`` bytes), lazy (``arg()`` gives the bytes),
    unreadable (``arg`` bytes, mode 000)."""

    kind: str
    arg: object = None


@dataclass
class Input:
    """One generated input and what it may end in."""

    id: str
    family: str
    files: dict = field(default_factory=dict)  # name -> bytes | str | Special
    argv: tuple = ()
    env: dict = field(default_factory=dict)  # name -> value, None = unset
    expect: frozenset = frozenset({2})
    names: tuple = ()  # text the Error line must hold (a key path, an option)
    out: str | None = OUT  # the folder that must stay empty on exit 2
    subprocess: bool = False  # run as `python -m xfemslip` (env read at import)
    timeout: float = 30.0
    stdin: bytes | None = None  # standard input of the command (None: empty)


def toml(doc: dict) -> str:
    return tomli_w.dumps(doc)


def key_name(path) -> str:
    """fractures[0].points: the key path as the error messages spell it."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out


# --------------------------------------------------------------------------- #
# Base cases
# --------------------------------------------------------------------------- #

SMALL = {
    "name": "small",
    "domain": {"size": [1.0, 1.0], "origin": [0.0, 0.0]},
    "mesh": {"elements": [4, 4]},
    "material": {"E": 1.0e9, "nu": 0.25, "model": "plane_strain"},
    "fractures": [
        {
            "points": [[0.2, 0.3], [0.8, 0.7]],
            "friction": 0.3,
            "cohesion": 0.0,
            "kn": 1.0e12,
            "kt": 1.0e12,
            "tip": "ramp",
        }
    ],
    "loading": {
        "stress": {"xx": -1.0e6, "yy": -2.0e6, "xy": 0.0},
        "initial_stress": {"xx": -1.0e6, "yy": -1.0e6, "xy": 0.0},
        "steps": 2,
    },
    "boundary": {"bottom": {"ux": 0.0, "uy": 0.0}, "top": "traction"},
    "solver": {
        "tolerance": 1.0e-8,
        "max_iterations": 30,
        "tangent": "consistent",
        "contact_patch": 1.5,
        "max_step_cuts": 5,
        "linear_solver": "superlu",
        "kernels": "numpy",
    },
    "output": {"formats": ["h5"]},
}

DEPLETION = {
    "name": "deplete-small",
    "domain": {"size": [1.0, 1.0]},
    "mesh": {"elements": [6, 6]},
    "material": {"E": 1.0e9, "nu": 0.25},
    "fractures": [
        {"center": [0.5, 0.5], "length": 0.5, "angle": 60.0, "friction": 0.5}
    ],
    "pore_pressure": {"initial": 1.0e6, "change": -1.0e6, "region": "all"},
    "loading": {
        "initial_stress": {"xx": -2.0e6, "yy": -4.0e6, "xy": 0.0},
        "stress": {"xx": -2.0e6, "yy": -4.0e6, "xy": 0.0},
        "steps": 2,
    },
    "boundary": {
        "left": {"ux": 0.0},
        "right": {"ux": 0.0},
        "bottom": {"uy": 0.0},
        "top": "traction",
    },
    "output": {"formats": ["h5"]},
}

GENERATE = {
    "seed": 3,
    "count": 4,
    "intersections": "allow",
    "outside": "clip",
    "orientation": {"distribution": "von_mises", "mean": 30.0, "kappa": 4.0},
    "length": {"distribution": "power_law", "exponent": 2.5, "min": 0.2, "max": 0.4},
}


def small(**changes) -> dict:
    doc = copy.deepcopy(SMALL)
    doc.update(changes)
    return doc


def network_case(generate: dict | None = None, file: str | None = None) -> dict:
    doc = small()
    del doc["fractures"]
    doc["mesh"] = {"elements": [8, 8]}
    doc["network"] = {"friction": 0.4, "tip": "ramp"}
    if generate is not None:
        doc["network"]["generate"] = generate
    if file is not None:
        doc["network"]["file"] = file
    return doc


BIG_INT_TEXT = "1" + "0" * 400


SWEEP = """\
name = "sw"
base = "base.toml"

[vary]
"fractures[0].friction" = [0.2, 0.4]
"""


def _lazy(body):
    """A file's text, or a Special that makes it when the input is written."""
    return body if isinstance(body, str) else Special("lazy", lambda: body().encode())
