"""The figure of ``xfemslip plot --figure permeability``: what the slip did to
the fractures' apertures and to the block's permeability.

Three panels of one result whose case has ``[permeability]``
(:mod:`xfemslip.post.hydraulics`):

- the hydraulic aperture [mm] along each fracture at the final step (the
  initial aperture a0 dotted);
- the cubic-law transmissivity a^3 / 12 [m^3] along each fracture (log scale);
- the block's k_xx and k_yy over their in-situ values against the load step,
  or against the pore-pressure change [MPa] when the case changes it (its
  magnitude to the right, as in every figure of a pressure change).

One legend below the panels.

The case's name is in the title.  matplotlib's object-oriented API only.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from xfemslip.errors import UsageError
from xfemslip.geometry.box import Box
from xfemslip.io.read import read_result
from xfemslip.plot.style import line_styles, pressure_change_axis

__all__ = ["figure_permeability", "load_axis"]


def _case(result) -> dict:
    try:
        case = tomllib.loads(str(result.attrs.get("case_toml", "")))
    except tomllib.TOMLDecodeError:
        return {}
    return case if isinstance(case, dict) else {}


def load_axis(result) -> tuple[np.ndarray, str]:
    """The x values of the ratio panel and their label: the pore-pressure
    change of each step [MPa] when the case changes it (its magnitude to the
    right, :func:`xfemslip.plot.style.pressure_change_axis`), else the load
    step."""
    case = _case(result)
    pore = case.get("pore_pressure", {})
    change = pore.get("change") if isinstance(pore, dict) else None
    factors = np.array([step.load_factor for step in result.steps])
    if isinstance(change, int | float) and change != 0:
        return pressure_change_axis(factors * float(change))
    return np.array([step.step for step in result.steps], float), "load step"


def figure_permeability(path: str | Path, label: str | None = None) -> Figure:
    """The figure of the module doc for the result at ``path`` (a result.h5 or
    its folder); UsageError when the result has no permeability."""
    result = read_result(path)
    if result.permeability is None or not result.steps:
        raise UsageError(
            f"{path}: no permeability in this result (its case has no "
            "[permeability] table, or no load step converged)"
        )
    name = _case(result).get("name") or label or Path(path).name
    history = result.permeability
    fig = Figure(figsize=(12.0, 3.8), layout="constrained")
    ax_a, ax_t, ax_k = fig.subplots(1, 3)
    styles = line_styles(len(result.fractures), dashes=True)
    for i, ff in enumerate(result.fractures):
        if ff.aperture is None or not np.size(ff.s):
            continue
        s = ff.s - ff.s.min()
        style = {"color": styles[i]["color"], "ls": styles[i]["linestyle"]}
        ax_a.plot(s, ff.aperture * 1e3, lw=1.4, label=f"fracture {i}", **style)
        a0 = float(history.initial_aperture[i])
        ax_a.plot([s.min(), s.max()], [a0 * 1e3] * 2, lw=0.8, **{**style, "ls": ":"})
        ax_t.semilogy(s, ff.transmissivity, lw=1.4, **style)
    ax_a.set_xlabel("distance along the fracture [m]")
    ax_a.set_ylabel("hydraulic aperture a [mm]")
    ax_a.set_title("aperture, final step (dotted: a0)", fontsize=9)
    ax_t.set_xlabel("distance along the fracture [m]")
    ax_t.set_ylabel("transmissivity a^3/12 [m^3]")
    ax_t.set_title("transmissivity per unit length, final step", fontsize=9)
    x, xlabel = load_axis(result)
    ratios = np.array([history.ratio(k) for k in range(len(result.steps))])
    x = np.concatenate([[0.0], x])
    ratios = np.vstack([[1.0, 1.0], ratios])
    ax_k.plot(x, ratios[:, 0], "o-", ms=3, label="k_xx / k_xx,0")
    ax_k.plot(x, ratios[:, 1], "s-", ms=3, label="k_yy / k_yy,0")
    ax_k.set_xlabel(xlabel + (" (0: in situ)" if xlabel == "load step" else ""))
    ax_k.set_ylabel("permeability / in situ [-]")
    x0, x1, y0, y1 = Box.from_corners(*history.block)
    ax_k.set_title(f"block [{x0:g}, {x1:g}] x [{y0:g}, {y1:g}] m (Oda)", fontsize=9)
    for ax in (ax_a, ax_t, ax_k):
        ax.grid(alpha=0.3)
    # below the panels, over no curve
    handles = ax_a.get_legend_handles_labels()
    ratio = ax_k.get_legend_handles_labels()
    fig.legend(
        handles[0] + ratio[0],
        handles[1] + ratio[1],
        loc="outside lower center",
        ncol=min(len(handles[0]) + 2, 6),
        fontsize=8,
    )
    fig.suptitle(f"{name}: permeability change from slip", fontsize=10)
    return fig
