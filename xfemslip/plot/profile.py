"""The figure of ``xfemslip plot --figure profile``: each fracture's profile
against depth (or height, or arc length for a horizontal fracture): the slip
that slid, the shear and effective normal tractions, the fluid pressure and
the Coulomb utilisation, at the last step (solid) and in situ (dashed, the
tractions and utilisation), with the stretches where the rock on its faces
changes marked (:mod:`xfemslip.post.profile`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from xfemslip.io.read import read_result
from xfemslip.post.profile import depth_datum, face_units

__all__ = ["MAX_PROFILES", "figure_profile"]

# fractures drawn, those that slid most first
MAX_PROFILES = 4
PANEL = (2.6, 3.6)  # width, height of one panel [in]


def _axis(result, ff):
    """(values (K,), label, inverted): depth below the datum, else height,
    else arc length along a horizontal fracture."""
    datum = depth_datum(result)
    y = ff.points[:, 1]
    if np.ptp(y) == 0.0:
        return ff.s, "arc length s [m]", False
    if datum is not None:
        return datum - y, "depth [m]", True
    return y, "y [m]", False


def _order(result) -> list[int]:
    """Fractures by the slip that slid at the last step, largest first."""
    last = result.steps[-1].fractures
    slid = [float(np.max(np.abs(f.slid), initial=0.0)) for f in last]
    return sorted(range(len(last)), key=lambda i: -slid[i])[:MAX_PROFILES]


def _mark_units(ax, prop, s, z) -> None:
    """Lines where the rock on a face changes, and the faces' units on each
    stretch (at its middle)."""
    if prop is None or prop.breaks is None or not len(prop.breaks):
        return
    at = np.interp(prop.breaks, s, z)
    for v in at:
        ax.axhline(v, color="0.6", lw=0.6, ls=":")
    edges = np.concatenate([[z[0]], at, [z[-1]]])
    plus, minus = face_units(prop, np.interp(0.5 * (edges[1:] + edges[:-1]), z, s))
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        text = plus[k] if plus[k] == minus[k] else f"{plus[k]} | {minus[k]}"
        ax.annotate(
            text,
            (1.0, 0.5 * (a + b)),
            xycoords=("axes fraction", "data"),
            xytext=(4, 0),
            textcoords="offset points",
            fontsize=6,
            va="center",
            color="0.35",
        )


def figure_profile(path: Path | str, label: str | None = None) -> Figure:
    """The profile figure of the result at ``path`` (result.h5)."""
    result = read_result(path)
    if not result.steps or not result.steps[-1].fractures:
        raise ValueError(f"{path}: no fracture to draw a profile of")
    order = _order(result)
    props = result.fracture_properties or []
    n = len(order)
    fig = Figure(figsize=(4 * PANEL[0] + 1.0, n * PANEL[1]), constrained_layout=True)
    axes = np.atleast_2d(fig.subplots(n, 4, sharey="row", squeeze=False))
    final = result.steps[-1]
    for row, i in enumerate(order):
        ff = final.fractures[i]
        prop = props[i] if i < len(props) else None
        z, zlabel, invert = _axis(result, ff)
        a0, a1, a2, a3 = axes[row]
        a0.plot(ff.slid * 1e3, z, "-", color="tab:orange", label="slid")
        a0.plot(ff.slip * 1e3, z, ":", color="0.5", lw=0.8, label="jump [[u]].t")
        a0.set_xlabel("slip [mm]")
        a0.set_ylabel(f"fracture {i}: {zlabel}")
        normal = (
            ff.effective_normal_traction
            if ff.effective_normal_traction is not None
            else ff.normal_traction
        )
        a1.plot(ff.shear_traction / 1e6, z, "-", color="tab:red", label="shear $p_T$")
        a1.plot(normal / 1e6, z, "-", color="tab:blue", label="normal $p_N'$")
        if (
            prop is not None
            and prop.in_situ_normal_traction is not None
            and prop.in_situ_shear_traction is not None
        ):
            a1.plot(prop.in_situ_shear_traction / 1e6, z, "--", color="tab:red", lw=0.8)
            a1.plot(
                prop.in_situ_normal_traction / 1e6, z, "--", color="tab:blue", lw=0.8
            )
        a1.set_xlabel("traction [MPa] (tension +)")
        if ff.fluid_pressure is not None:
            a2.plot(ff.fluid_pressure / 1e6, z, "-", color="tab:cyan")
            a2.set_xlabel("fluid pressure [MPa]")
        else:
            a2.text(0.5, 0.5, "no pore pressure", transform=a2.transAxes, ha="center")
            a2.set_xlabel("fluid pressure")
        if ff.utilisation is not None:
            a3.plot(ff.utilisation, z, "-", color="k", label="last step")
        if prop is not None and prop.in_situ_utilisation is not None:
            a3.plot(
                prop.in_situ_utilisation, z, "--", color="0.4", lw=0.8, label="in situ"
            )
        a3.set_xlim(0.0, 1.05)
        a3.set_xlabel("Coulomb utilisation [-]")
        _mark_units(a3, prop, ff.s, z)
        for ax in axes[row]:
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
        if invert:
            a0.invert_yaxis()
        if row == 0:
            for ax in (a0, a1, a3):
                ax.legend(fontsize=6, loc="best")
    lam = final.load_factor
    fig.suptitle(
        f"{label or Path(path).parent.name}: profiles along the fractures at load "
        f"factor {lam:.3g} (dashed: in situ)",
        fontsize=9,
    )
    return fig
