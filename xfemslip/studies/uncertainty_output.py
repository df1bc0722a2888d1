"""The files and the printed summary of an uncertainty study.

``write_outputs(result, directory)`` writes one set (replaced together,
:func:`xfemslip.io.fileset.replace_files`): ``uncertainty.csv`` (one row per
sample), ``probability.csv`` (per fracture and level), ``sensitivity.csv``
(per fracture and input), ``uncertainty.h5`` (the same arrays with units
attrs) and ``probability.png`` (matplotlib imported only then).  Columns and
datasets: docs/sweep-format.md, *Uncertainty*.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from xfemslip import display
from xfemslip.io.csv import write_rows
from xfemslip.io.fileset import replace_files

SAMPLES_CSV = "uncertainty.csv"
PROBABILITY_CSV = "probability.csv"
SENSITIVITY_CSV = "sensitivity.csv"
RESULT_H5 = "uncertainty.h5"
FIGURE = "probability.png"
# Units of an input by the last name of its key path (as the case format
# reads it); any other key is in the case format's unit of that key.
INPUT_UNITS = {
    "friction": "1",
    "cohesion": "Pa",
    "angle": "deg",
    "length": "m",
    "xx": "Pa",
    "yy": "Pa",
    "xy": "Pa",
    "initial": "Pa",
    "biot": "1",
    "nu": "1",
    "E": "Pa",
    "kn": "Pa/m",
    "kt": "Pa/m",
}


def input_unit(key: str) -> str:
    """Unit of an input key path ("" when the case format gives none here)."""
    return INPUT_UNITS.get(key.rsplit(".", 1)[-1], "")


def _g(value) -> str:
    """A number cell: empty for NaN."""
    return "" if not np.isfinite(value) else f"{value:.9g}"


def write_samples(path: Path, result) -> None:
    """uncertainty.csv: sample, inputs, status, per fracture dp_critical
    (and max slip and slipping length with xfem), error."""
    spec = result.spec
    frac = result.fractures
    header = ["sample", *spec.keys, "status"]
    header += [f"dp_critical_{i}_Pa" for i in frac]
    if result.max_slip is not None:
        header += [f"max_slip_{i}_m" for i in frac]
        header += [f"slip_length_{i}_m" for i in frac]
    header.append("error")
    write_rows(path, header, _sample_rows(result))


def _sample_rows(result):
    """The rows of uncertainty.csv, one at a time (a million samples would
    otherwise hold ~1 GB of cell strings)."""
    spec = result.spec
    for s in range(spec.samples):
        row = [result.ids[s], *(f"{v:.9g}" for v in spec.values[s]), result.status[s]]
        row += [_g(v) for v in result.dp_critical[s]]
        if result.max_slip is not None:
            row += [_g(v) for v in result.max_slip[s]]
            row += [_g(v) for v in result.slip_length[s]]
        row.append(result.errors[s])
        yield row


def write_probability(path: Path, result) -> None:
    """probability.csv: per fracture and level, P with its Wilson interval."""
    header = [
        "fracture",
        "dp_Pa",
        "samples",
        "slipped",
        "probability",
        "ci_low",
        "ci_high",
        "half_width",
        "samples_needed",
    ]
    rows = []
    for j, fi in enumerate(result.fractures):
        for k, level in enumerate(result.spec.levels):
            lo, hi = result.ci_low[j, k], result.ci_high[j, k]
            rows.append(
                [
                    fi,
                    f"{level:.9g}",
                    result.evaluated,
                    int(result.slipped[j, k]),
                    _g(result.probability[j, k]),
                    _g(lo),
                    _g(hi),
                    _g(0.5 * (hi - lo)),
                    int(result.samples_needed[j, k]),
                ]
            )
    write_rows(path, header, rows)


def write_sensitivity(path: Path, result) -> None:
    """sensitivity.csv: Spearman correlation of each input with dp_critical."""
    rows = [
        [fi, key, _g(result.sensitivity[j, k])]
        for j, fi in enumerate(result.fractures)
        for k, key in enumerate(result.spec.keys)
    ]
    write_rows(path, ["fracture", "input", "spearman_dp_critical"], rows)


def write_h5(path: Path, result) -> None:
    """uncertainty.h5: the arrays of the CSV files, each with attrs["units"]."""
    import h5py

    spec = result.spec
    with h5py.File(path, "w") as h5:
        h5.attrs["name"] = spec.name
        h5.attrs["evaluate"] = spec.evaluate
        h5.attrs["method"] = spec.method
        h5.attrs["seed"] = spec.seed
        h5.attrs["confidence"] = spec.confidence
        h5.attrs["half_width"] = spec.half_width
        h5.attrs["stress_path"] = result.path_text
        h5.attrs["evaluated"] = result.evaluated
        h5.attrs["compute_time_s"] = result.compute_time_s

        def put(name, data, units, **attrs):
            ds = h5.create_dataset(name, data=data)
            ds.attrs["units"] = units
            for k, v in attrs.items():
                ds.attrs[k] = v

        put(
            "inputs",
            spec.values,
            "see input_units",
            keys=np.array(spec.keys, dtype="S"),
            input_units=np.array([input_unit(k) for k in spec.keys], dtype="S"),
        )
        put("status", np.array(result.status, dtype="S"), "")
        put("fractures", np.array(result.fractures, dtype=np.int64), "")
        put("levels", spec.levels, "Pa")
        put("dp_critical", result.dp_critical, "Pa")
        if result.max_slip is not None:
            put("max_slip", result.max_slip, "m")
            put("slip_length", result.slip_length, "m")
        put("slipped", result.slipped, "1")
        put("probability", result.probability, "1")
        put("ci_low", result.ci_low, "1")
        put("ci_high", result.ci_high, "1")
        put("samples_needed", result.samples_needed, "1")
        put("sensitivity", result.sensitivity, "1")


def write_outputs(result, directory: Path, *, figure: bool = True) -> list[Path]:
    """The whole set into ``directory`` (created); returns the paths."""
    from xfemslip.errors import OutputError

    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot write {directory}: {exc.strerror}") from None
    # each writes one file to the path it is given (what it returns is unused)
    writes: dict[Path, Callable[[Path], object] | None] = {
        directory / SAMPLES_CSV: lambda p: write_samples(p, result),
        directory / PROBABILITY_CSV: lambda p: write_probability(p, result),
        directory / SENSITIVITY_CSV: lambda p: write_sensitivity(p, result),
        directory / RESULT_H5: lambda p: write_h5(p, result),
    }
    if figure:
        from xfemslip.plot.probability import plot_probability

        writes[directory / FIGURE] = lambda p: plot_probability(result, p)
    return replace_files(writes)


# --------------------------------------------------------------------------- #
# Printed summary
# --------------------------------------------------------------------------- #

MAX_ROWS = 11  # levels shown in the printed table (all are in the CSV)


def format_summary(result) -> str:
    """The text the CLI prints: what was assumed, P per level, sensitivity."""
    spec = result.spec
    counts = {
        s: int(np.sum(result.status == s))
        for s in ("ok", "skipped", "refused", "failed")
    }
    lines = [
        f"{spec.name}: {spec.samples} samples ({spec.method}, seed {spec.seed}), "
        f"evaluate = {spec.evaluate}: {result.evaluated} evaluated "
        f"({counts['skipped']} read back), {counts['refused']} refused, "
        f"{counts['failed']} failed; {result.compute_time_s:.3g} s",
        result.path_text,
        f"probability that each fracture has slipped by a pore-pressure change "
        f"dp, with its {spec.confidence:.0%} Wilson interval and the samples a "
        f"half-width of {spec.half_width:g} needs:",
    ]
    shown = np.unique(
        np.linspace(0, len(spec.levels) - 1, MAX_ROWS).round().astype(int)
    )
    for j, fi in enumerate(result.fractures):
        lines.append(f"  fracture {fi}:")
        rows = [
            [
                f"{spec.levels[k] / 1e6:.3g}",
                f"{result.probability[j, k]:.3f}",
                f"[{result.ci_low[j, k]:.3f}, {result.ci_high[j, k]:.3f}]",
                str(result.samples_needed[j, k]),
            ]
            for k in shown
        ]
        table = display.table(["dp [MPa]", "P", "interval", "needs"], rows)
        lines.extend(f"    {line}" for line in table.splitlines())
        if len(spec.keys):
            lines.append(_sensitivity_line(spec.keys, result.sensitivity[j]))
        if result.max_slip is not None:
            lines.append(_slip_line(result, j))
    return "\n".join(lines)


def _sensitivity_line(keys, rho) -> str:
    """The input with the largest |Spearman rho|, or why there is none: a
    rank correlation is undefined (NaN) over fewer than two evaluated
    samples, or when the input or dp_critical does not vary over them."""
    rho = np.asarray(rho, float)
    if not np.any(np.isfinite(rho)):
        return (
            "    sensitivity: not defined (the Spearman correlation needs at "
            "least two evaluated samples in which the input and dp_critical vary)"
        )
    k = int(np.nanargmax(np.abs(rho)))
    return f"    most sensitive to {keys[k]} (Spearman with dp_critical {rho[k]:+.3f})"


def _slip_line(result, j: int) -> str:
    """Quantiles of max slip and slipping length at the final step."""
    use = np.isin(result.status, ("ok", "skipped"))
    s = result.max_slip[use, j]
    length = result.slip_length[use, j]
    if s.size == 0:
        return "    no evaluated sample"
    q = np.percentile(s, [5, 50, 95]) * 1e3
    ql = np.percentile(length, [5, 50, 95])
    return (
        f"    at the final step: max slip 5/50/95% = {q[0]:.3g}/{q[1]:.3g}/"
        f"{q[2]:.3g} mm, slipping length {ql[0]:.3g}/{ql[1]:.3g}/{ql[2]:.3g} m"
    )
