"""Whether a ``result.h5`` can be trusted: the checks around its reader.

:func:`xfemslip.io.read.read_result` reads a file that may be damaged
(flipped bits, cut short), partial, or written by something else.  Every
way such a file can fail is turned into one
:class:`~xfemslip.errors.ResultError` naming the file and what is wrong, in
three places:

- :func:`check_layout`, before any array is read: every dataset's declared
  size fits in the file (a damaged header cannot make the reader allocate
  more than the file holds), and the groups that the format numbers
  (``/steps/<k>``, ``/fractures/<i>``) have decimal names;
- :func:`reading`, around the reading itself: an error of HDF5 (a checksum,
  a truncated file), a dataset or attribute missing, a value of the wrong
  type;
- :func:`check_final_copy`: a file of several load steps holds the final
  step's displacement and fracture fields twice, at the root and in
  ``/steps``; both copies must be the same (a reader of either sees one run);
- :func:`check_result`, on what was read: the shapes the output format
  gives (one row per node, cell, contact point, converged step, fracture),
  cells that name existing nodes, contact states 0, 1 or 2, finite numbers
  everywhere the writers refuse non-finite ones (a stress drop may be NaN:
  the crack model has none without a slipping length), positive initial
  apertures, a block with x0 < x1 and y0 < y1.

Arrays a newer writer adds to a fracture or a step are checked like their
neighbours: one row per contact point (or node, or cell), finite.
"""

from __future__ import annotations

import contextlib
import os
import re
import tomllib
from collections.abc import Iterator
from dataclasses import fields
from pathlib import Path

import h5py
import numpy as np

from xfemslip.conventions import OPEN, SLIP, STICK
from xfemslip.errors import ResultError
from xfemslip.post.fields import FractureProperties

__all__ = ["check_final_copy", "check_layout", "check_result", "reading"]

# A dataset is stored uncompressed by the writer; a foreign file may
# compress, but not beyond this ratio (a header claiming more is damaged).
MAX_COMPRESSION = 1000
# Root attributes a result needs and how each must read.
REQUIRED_ATTRS = {
    "converged": (bool, np.bool_),
    "load_steps": (int, np.integer),
    "newton_iterations": (int, np.integer),
    "case_toml": (str,),
}
_NUMBERED = re.compile(r"^(?:/steps|.*/fractures)$")


def _bad(path: Path, what: str) -> ResultError:
    return ResultError(f"{path}: not a result.h5 of xfemslip: {what}")


@contextlib.contextmanager
def reading(path: Path) -> Iterator[None]:
    """Errors of reading ``path`` as one ResultError naming the file."""
    try:
        yield
    except ResultError:
        raise
    except (OSError, RuntimeError) as exc:  # HDF5: checksums, truncation
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ResultError(f"{path}: not a readable result.h5: {reason}") from None
    except KeyError as exc:
        name = str(exc.args[0]) if exc.args else ""
        what = f"{name!r} is missing" if name else "a dataset is missing"
        raise _bad(path, what) from None
    except (ValueError, TypeError, IndexError, UnicodeError, OverflowError) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise _bad(path, reason) from None


def check_layout(h5: h5py.File, path: Path) -> None:
    """Before reading arrays: declared sizes and the numbered groups."""
    limit = os.path.getsize(path) + 2**20

    def visit(name: str, item) -> None:
        if isinstance(item, h5py.Dataset):
            declared = int(np.prod(item.shape, dtype=np.float64) * item.dtype.itemsize)
            factor = MAX_COMPRESSION if item.chunks is not None else 1
            if declared > factor * limit:
                raise _bad(
                    path,
                    f"/{name} declares {declared} bytes, more than the file "
                    f"holds ({limit - 2**20} bytes)",
                )
        elif isinstance(item, h5py.Group) and _NUMBERED.match(f"/{name}"):
            for child in item:
                if not child.isdigit():
                    raise _bad(
                        path,
                        f"/{name}/{child}: expected a group numbered 0, 1, ... "
                        f"(a {'load step' if name == 'steps' else 'fracture'})",
                    )

    with reading(path):
        h5.visititems(visit)


# data sets of /fractures/<i> that the root holds alone (FractureProperties)
ROOT_ONLY = frozenset(f.name for f in fields(FractureProperties))


def check_final_copy(h5: h5py.File, path: Path) -> None:
    """The root copy of the final step equals its ``/steps`` group."""
    if "steps" not in h5 or not len(h5["steps"]):
        return
    last = h5["steps"][sorted(h5["steps"], key=int)[-1]]
    pairs = [("fields/displacement", "fields/displacement")]
    if "fractures" in last or "fractures" in h5:
        if "fractures" not in last or "fractures" not in h5:
            raise _bad(path, "/fractures and the final step's fractures differ")
        ours, theirs = h5["fractures"], last["fractures"]
        if sorted(ours) != sorted(theirs):
            raise _bad(path, "/fractures and the final step's fractures differ")
        for index in theirs:
            # the fracture's properties are kept at the root only
            names = (set(theirs[index]) | set(ours[index])) - ROOT_ONLY
            pairs += [
                (f"fractures/{index}/{n}", f"fractures/{index}/{n}") for n in names
            ]
    for root_name, step_name in sorted(pairs):
        if root_name not in h5 or step_name not in last:
            raise _bad(path, f"/{root_name}: missing at the root or in the final step")
        a, b = h5[root_name], last[step_name]
        if a.shape != b.shape or not np.array_equal(a[()], b[()]):
            raise _bad(
                path,
                f"/{root_name} differs from its copy in the final step {last.name}",
            )


def check_attrs(attrs: dict, path: Path) -> None:
    """The root attributes a result needs, of the right type."""
    for name, types in REQUIRED_ATTRS.items():
        if name not in attrs:
            raise _bad(path, f"the root attribute {name!r} is missing")
        value = attrs[name]
        if not isinstance(value, types) or (
            bool not in types and isinstance(value, bool)
        ):
            raise _bad(path, f"the root attribute {name!r} is {value!r}")
    if attrs["load_steps"] < 1 or attrs["newton_iterations"] < 0:
        raise _bad(
            path,
            f"load_steps = {attrs['load_steps']}, newton_iterations = "
            f"{attrs['newton_iterations']}",
        )
    if "run_id" in attrs and not isinstance(attrs["run_id"], int | np.integer):
        raise _bad(path, f"the root attribute 'run_id' is {attrs['run_id']!r}")
    try:
        tomllib.loads(attrs["case_toml"])
    except tomllib.TOMLDecodeError as exc:
        raise _bad(path, f"the case text case_toml is not TOML ({exc})") from None


def _array(value, where: str, path: Path, shape: tuple, *, finite=True, ints=False):
    """``value`` as an array of ``shape`` (None: any length)."""
    array = np.asarray(value)
    ok = array.ndim == len(shape) and all(
        want in (None, got) for want, got in zip(shape, array.shape, strict=True)
    )
    if not ok:
        want = "(" + ", ".join("*" if n is None else str(n) for n in shape) + ")"
        raise _bad(path, f"{where} has shape {array.shape}, expected {want}")
    kind = "iu" if ints else "biuf"
    if array.dtype.kind not in kind:
        raise _bad(path, f"{where} holds {array.dtype} values, expected numbers")
    if finite and array.dtype.kind == "f" and not np.all(np.isfinite(array)):
        raise _bad(path, f"{where} holds NaN or inf")
    return array


def _check_fracture(fracture, where: str, path: Path) -> int:
    """One fracture's arrays: K contact points each; returns K."""
    k = _array(fracture.s, f"{where}/s", path, (None,)).shape[0]
    for item in fields(fracture):
        value = getattr(fracture, item.name)
        if value is None or item.name == "s":
            continue
        shape: tuple[int | None, ...] = (k, 2) if item.name == "points" else (k,)
        if item.name != "points" and np.ndim(value) == 2:
            shape = (k, None)
        array = _array(value, f"{where}/{item.name}", path, shape)
        if item.name == "state" and not np.all(np.isin(array, (OPEN, STICK, SLIP))):
            raise _bad(path, f"{where}/state holds codes other than 0, 1, 2")
    return k


def check_result(result, path: Path) -> None:
    """What was read, against the output format (module doc)."""
    check_attrs(result.attrs, path)
    points = _array(result.points, "/mesh/points", path, (None, 2))
    cells = _array(result.cells, "/mesh/cells", path, (None, 4), ints=True)
    n, m = len(points), len(cells)
    if cells.size and (cells.min() < 0 or cells.max() >= n):
        raise _bad(path, f"/mesh/cells names nodes outside 0 .. {n - 1}")
    steps = result.steps
    if len(steps) > result.attrs["load_steps"]:
        raise _bad(
            path,
            f"{len(steps)} converged steps, more than load_steps = "
            f"{result.attrs['load_steps']}",
        )
    numbers = [step.step for step in steps]
    if numbers != sorted(set(numbers)) or (numbers and numbers[0] < 1):
        raise _bad(path, f"the steps are numbered {numbers[:10]}")
    counts = set()
    for step in steps:
        where = f"step {step.step}"
        if not np.isfinite(step.load_factor) or step.newton_iterations < 0:
            raise _bad(path, f"{where}: load_factor {step.load_factor!r}")
        _array(step.displacement, f"{where} displacement", path, (n, 2))
        for item in ("stress", "effective_stress", "principal_stress"):
            value = getattr(step, item, None)
            if value is not None:
                _array(value, f"{where} {item}", path, (m, None))
        for item in ("stress_zz", "pore_pressure"):
            value = getattr(step, item, None)
            if value is not None:
                _array(value, f"{where} {item}", path, (m,))
        counts.add(len(step.fractures))
        for i, fracture in enumerate(step.fractures):
            _check_fracture(fracture, f"{where} fracture {i}", path)
    if len(counts) > 1:
        raise _bad(path, f"the steps hold different numbers of fractures {counts}")
    n_fractures = counts.pop() if counts else 0
    if steps and steps[-1].stress is None:
        raise _bad(path, "the final step has no element stresses")
    _check_events(result.events, len(steps), n_fractures, path)
    _check_permeability(result.permeability, len(steps), n_fractures, path)


def _check_events(events, n_steps: int, n_fractures: int, path: Path) -> None:
    if events is None:
        return
    for item in fields(events):
        value = getattr(events, item.name)
        if isinstance(value, bool | np.bool_):
            continue
        # no stress drop without a slipping length: NaN there
        finite = item.name != "stress_drop"
        array = _array(value, f"/events/{item.name}", path, (None, None), finite=finite)
        if array.shape != (n_steps, n_fractures):
            raise _bad(
                path,
                f"/events/{item.name} has shape {array.shape}, expected "
                f"({n_steps}, {n_fractures}): one row per converged step, one "
                "column per fracture",
            )


def _check_permeability(history, n_steps: int, n_fractures: int, path: Path) -> None:
    if history is None:
        return
    _array(history.in_situ, "/permeability/in_situ", path, (2, 2))
    _array(history.tensors, "/permeability/tensor", path, (n_steps, 2, 2))
    a0 = _array(
        history.initial_aperture,
        "/permeability/initial_aperture",
        path,
        (n_fractures,),
    )
    if np.any(a0 <= 0.0):
        raise _bad(path, "/permeability/initial_aperture holds a value <= 0")
    block = _array(history.block, "/permeability block", path, (4,))
    if not (block[0] < block[2] and block[1] < block[3]):
        raise _bad(path, f"/permeability block {list(block)}: not x0 < x1, y0 < y1")
    if not (np.isfinite(history.matrix) and history.matrix >= 0.0):
        raise _bad(path, f"/permeability matrix {history.matrix!r}")
