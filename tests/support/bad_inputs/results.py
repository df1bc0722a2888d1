"""Result families of the bad-input suite: ``result.h5`` files that are
corrupted (flipped bits), truncated, partial (a dataset, attribute or row
missing) or foreign (another program's HDF5, another run's VTU beside it,
a case file), read by every command that reads a result (``summary``,
``plot`` and its figures, ``dfn --result``).

The source files come from one real run of a small case with pore
pressure, ``[permeability]`` and ``[events]`` over two load steps (so that
``/steps``, ``/events`` and ``/permeability`` are all there), made once per
process; each input is a damaged copy, made when the input is written.
"""

from __future__ import annotations

import copy
import functools
import io
import random
import tempfile
from pathlib import Path

import h5py
import numpy as np

from tests.support.bad_inputs.base import DEPLETION, Input, Special, network_case, toml

FIGURES = "figs"  # the plot output folder: empty after a refusal


def _case(friction: float = 0.5) -> dict:
    doc = copy.deepcopy(DEPLETION)
    doc["fractures"][0]["friction"] = friction
    doc["permeability"] = {"aperture": 1.0e-4, "dilation_angle": 5.0}
    doc["events"] = {"extent": 100.0}
    doc["output"] = {"formats": ["h5", "vtu"]}
    return doc


@functools.cache
def source(friction: float = 0.5) -> dict[str, bytes]:
    """The files of one run (name -> bytes): result.h5, result.vtu, case.toml."""
    import xfemslip
    from xfemslip.case import loads_case

    text = toml(_case(friction))
    with tempfile.TemporaryDirectory() as tmp:
        case = Path(tmp) / "case.toml"
        case.write_text(text)
        out = Path(tmp) / "out"
        xfemslip.run_case(loads_case(text, case), out)
        return {
            "result.h5": (out / "result.h5").read_bytes(),
            "result.vtu": (out / "result.vtu").read_bytes(),
            "case.toml": text.encode(),
        }


@functools.cache
def network_source() -> dict[str, bytes]:
    """A run of a small generated network (for ``dfn --result``)."""
    import xfemslip
    from xfemslip.case import loads_case

    text = toml(network_case(generate=_GENERATE))
    with tempfile.TemporaryDirectory() as tmp:
        case = Path(tmp) / "case.toml"
        case.write_text(text)
        out = Path(tmp) / "out"
        xfemslip.run_case(loads_case(text, case), out)
        return {
            "result.h5": (out / "result.h5").read_bytes(),
            "case.toml": text.encode(),
        }


_GENERATE = {
    "seed": 3,
    "count": 3,
    "intersections": "avoid",
    "outside": "clip",
    "orientation": {"distribution": "von_mises", "mean": 30.0, "kappa": 4.0},
    "length": {"distribution": "constant", "value": 0.3},
}


def _edited(data: bytes, edit) -> bytes:
    """``data`` (an HDF5 file) after ``edit(h5)``, written anew."""
    buffer = io.BytesIO(data)
    with h5py.File(buffer, "r+") as h5:
        edit(h5)
    return buffer.getvalue()


def _replace(name: str, value):
    def edit(h5):
        attrs = dict(h5[name].attrs)
        del h5[name]
        h5[name] = value
        h5[name].attrs.update(attrs)

    return edit


def _rename(old: str, new: str):
    def edit(h5):
        h5.move(old, new)

    return edit


def _attr(name: str, value=None, delete=False, where: str = "/"):
    def edit(h5):
        if delete:
            del h5[where].attrs[name]
        else:
            h5[where].attrs[name] = value

    return edit


def _rows_short(name: str, axis: int = 0):
    def edit(h5):
        value = h5[name][()]
        index = [slice(None)] * value.ndim
        index[axis] = slice(0, value.shape[axis] - 1)
        _replace(name, value[tuple(index)])(h5)

    return edit


def _scaled(name: str, factor, offset=0.0):
    def edit(h5):
        _replace(name, h5[name][()] * factor + offset)(h5)

    return edit


def _cells_out_of_range(h5):
    cells = h5["mesh/cells"][()]
    cells[0, 0] = len(h5["mesh/points"]) + 5
    _replace("mesh/cells", cells)(h5)


def _nan_point(h5):
    points = h5["mesh/points"][()]
    points[3, 1] = np.nan
    _replace("mesh/points", points)(h5)


def _state_7(h5):
    state = h5["fractures/0/state"][()]
    state[0] = 7
    _replace("fractures/0/state", state)(h5)


def _foreign_case(h5):
    doc = _case()
    doc["fractures"].append(
        {"center": [0.5, 0.2], "length": 0.2, "angle": 10.0, "friction": 0.5}
    )
    h5.attrs["case_toml"] = toml(doc)


def _no_steps_converged(h5):
    for name in ("steps", "fields", "fractures", "events", "permeability"):
        if name in h5:
            del h5[name]
    h5.attrs["converged"] = False


# name -> edit of result.h5 (each makes a file that is not a valid result,
# except the last group, which a reader may still read)
EDITS = {
    "no-converged": _attr("converged", delete=True),
    "no-load_steps": _attr("load_steps", delete=True),
    "no-newton_iterations": _attr("newton_iterations", delete=True),
    "no-case_toml": _attr("case_toml", delete=True),
    "converged-string": _attr("converged", "yes"),
    "load_steps-0": _attr("load_steps", 0),
    "load_steps-1-of-2": _attr("load_steps", 1),
    "events-row-short": _rows_short("events/max_slip"),
    "events-column-short": _rows_short("events/slipped", axis=1),
    "events-extent-nan": _scaled("events/extent", np.nan),
    "step-named-two": _rename("steps/0002", "steps/two"),
    "step-named-minus-1": _rename("steps/0001", "steps/-1"),
    "fracture-named-x": _rename("fractures/0", "fractures/x"),
    "initial-aperture-0": _scaled("permeability/initial_aperture", 0.0),
    "initial-aperture-short": _rows_short("permeability/initial_aperture"),
    "tensor-inf": _scaled("permeability/tensor", np.inf),
    "block-reversed": _attr(
        "block", np.array([1.0, 1.0, 0.0, 0.0]), where="permeability"
    ),
    "cells-out-of-range": _cells_out_of_range,
    "points-nan": _nan_point,
    "displacement-3-columns": lambda h5: _replace(
        "fields/displacement", np.zeros((len(h5["mesh/points"]), 3))
    )(h5),
    "displacement-missing": lambda h5: h5.__delitem__("fields/displacement"),
    "stress-missing": lambda h5: h5.__delitem__("fields/stress"),
    "state-7": _state_7,
    "slip-row-short": _rows_short("fractures/0/slip"),
    "slip-strings": _replace("fractures/0/slip", np.array([b"x"] * 4)),
    "case-not-toml": _attr("case_toml", "[[[ not toml"),
    "step-displacement-3-columns": lambda h5: _replace(
        "steps/0002/fields/displacement", np.zeros((len(h5["mesh/points"]), 3))
    )(h5),
    "step-slip-row-short": _rows_short("steps/0002/fractures/0/slip"),
    "step-load-factor-nan": _attr("load_factor", np.nan, where="steps/0001"),
    "mesh-missing": lambda h5: h5.__delitem__("mesh"),
}
PERMEABILITY_EDITS = (
    "initial-aperture-0",
    "initial-aperture-short",
    "tensor-inf",
    "block-reversed",
)
# edits after which the file is still a result (exit 0 or a refusal)
READABLE_EDITS = {
    "case-of-another-case": _foreign_case,
    "no-step-converged": _no_steps_converged,
    "first-step-missing": lambda h5: h5.__delitem__("steps/0001"),
}


def _empty_h5() -> bytes:
    buffer = io.BytesIO()
    with h5py.File(buffer, "w"):
        pass
    return buffer.getvalue()


def _other_h5() -> bytes:
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as h5:
        h5["data"] = np.arange(10.0)
        h5.attrs["converged"] = True
    return buffer.getvalue()


SOURCES = {"case": source, "network": network_source}


def _flipped(kind: str, seed: int, count: int) -> bytes:
    """``count`` bits flipped at random places of the source result.h5."""
    data = bytearray(SOURCES[kind]()["result.h5"])
    rng = random.Random(seed)
    for _ in range(count):
        k = rng.randrange(len(data))
        data[k] ^= 1 << rng.randrange(8)
    return bytes(data)


def _truncated(kind: str, fraction: float) -> bytes:
    data = SOURCES[kind]()["result.h5"]
    return data[: int(len(data) * fraction)]


def _files(kind: str = "case") -> dict[str, tuple[object, frozenset]]:
    """name -> (result.h5 content, allowed exit codes), damaged copies of
    the result of SOURCES[kind]."""
    refuse, either = frozenset({2}), frozenset({0, 2})
    out = {
        name: (Special("lazy", functools.partial(_edited_source, kind, edit)), refuse)
        for name, edit in EDITS.items()
        if kind == "case" or name not in PERMEABILITY_EDITS
    }
    out |= {
        name: (Special("lazy", functools.partial(_edited_source, kind, edit)), either)
        for name, edit in READABLE_EDITS.items()
    }
    out["empty-hdf5"] = (Special("lazy", _empty_h5), refuse)
    out["other-hdf5"] = (Special("lazy", _other_h5), refuse)
    out["text"] = (b"not an HDF5 file\n", refuse)
    out["zero-bytes"] = (b"", refuse)
    out["case-file"] = (Special("lazy", lambda: source()["case.toml"]), refuse)
    for fraction in (0.1, 0.5, 0.9, 0.99):
        out[f"truncated-{fraction:g}"] = (
            Special("lazy", functools.partial(_truncated, kind, fraction)),
            refuse,
        )
    for seed in range(12):
        out[f"bits-{seed}"] = (
            Special("lazy", functools.partial(_flipped, kind, seed, 1 + seed % 3)),
            either,
        )
    return out


def _edited_source(kind: str, edit) -> bytes:
    return _edited(SOURCES[kind]()["result.h5"], edit)


COMMANDS = {
    "summary": ("summary", "result.h5"),
    "summary-steps": ("summary", "--steps", "result.h5"),
    "plot": ("plot", "result.h5", "-o", FIGURES, "--format", "png", "--figure", "slip"),
    "plot-all": ("plot", "result.h5", "-o", FIGURES, "--format", "png"),
    "plot-permeability": (
        "plot",
        "result.h5",
        "-o",
        FIGURES,
        "--format",
        "png",
        "--figure",
        "permeability",
    ),
}


def result_inputs() -> list[Input]:
    """Every damaged result through every command that reads one."""
    out = []
    for name, (content, expect) in _files().items():
        for command, argv in COMMANDS.items():
            out.append(
                Input(
                    id=f"result/{command}/{name}",
                    family="result-files",
                    files={"result.h5": content},
                    argv=argv,
                    expect=expect,
                    names=("result.h5",),
                    out=FIGURES if command.startswith("plot") else None,
                    timeout=60.0,
                )
            )
    network = Special("lazy", lambda: network_source()["case.toml"])
    for name, (content, expect) in _files("network").items():
        out.append(
            Input(
                id=f"result/dfn/{name}",
                family="result-files",
                files={"result.h5": content, "case.toml": network},
                argv=("dfn", "case.toml", "--plot", "net.png", "--result", "result.h5"),
                expect=expect,
                names=("result.h5",),
                out=None,
                timeout=60.0,
            )
        )
    return out
