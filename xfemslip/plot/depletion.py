"""Figures of ``xfemslip deplete``: slip vs depletion and a field picture.

Imported only when plotting (matplotlib is not a dependency of a run).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from xfemslip.conventions import SLIP
from xfemslip.geometry.regions import edges


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_slip_vs_depletion(
    report, out_dir: Path, dpi: float = 110.0, name: str | None = None
) -> Path:
    """Max |slip| that slid and slipping length of each fracture against the
    pressure drop (``report.rows``, the event sizes); ``name`` (the case's)
    titles the figure."""
    plt = _pyplot()
    rows = report.rows
    drop = np.array([-r[2] for r in rows]) / 1e6  # pressure drop [MPa]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9.0, 3.6), constrained_layout=True)
    for i, onset in enumerate(report.onsets):
        slip = np.array([r[3][i][0] for r in rows]) * 1e3
        length = np.array([r[3][i][1] for r in rows])
        (line,) = a1.plot(drop, slip, "o-", ms=3, label=f"fracture {onset.fracture}")
        a2.plot(drop, length, "o-", ms=3, color=line.get_color())
        if np.isfinite(onset.dp_upper):
            for ax in (a1, a2):
                ax.axvline(-onset.dp_critical / 1e6, color=line.get_color(), ls=":")
    a1.set_xlabel("pore-pressure drop $-\\Delta p$ [MPa]")
    a1.set_ylabel("max |slip| that slid [mm]")
    a2.set_xlabel("pore-pressure drop $-\\Delta p$ [MPa]")
    a2.set_ylabel("slipping length [m]")
    a1.legend(fontsize=8)
    a1.set_title("dotted: critical depletion (bisection)", fontsize=9)
    if name:
        fig.suptitle(f"{name}: slip against depletion", fontsize=10)
    path = out_dir / "slip_vs_depletion.png"
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_field(model, result, out_dir: Path, dpi: float = 110.0) -> Path:
    """Shear stress change and effective horizontal stress at the last step,
    reservoir outline, fractures coloured stick / slip."""
    from xfemslip.post.fields import cell_in_situ, step_fields

    plt = _pyplot()
    f = step_fields(model, result)
    mesh = model.mesh
    s0 = cell_in_situ(model)
    s0 = np.zeros(3) if s0 is None else np.atleast_2d(np.asarray(s0, float))
    shape = (mesh.ny, mesh.nx)
    stress = f.stress
    assert stress is not None  # step_fields computes the stresses
    panels = [
        (
            "shear stress change $\\Delta\\sigma_{xy}$ [MPa]",
            stress[:, 2] - np.broadcast_to(s0, stress.shape)[:, 2],
        ),
        (
            "effective stress $\\sigma'_{xx}$ [MPa]",
            f.effective_stress[:, 0]
            if f.effective_stress is not None
            else stress[:, 0],
        ),
    ]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.2), constrained_layout=True)
    for ax, (title, value) in zip(axes, panels, strict=True):
        v = value.reshape(shape) / 1e6
        lim = np.max(np.abs(v - np.median(v))) or 1.0
        mid = np.median(v) if "effective" in title else 0.0
        im = ax.pcolormesh(
            mesh.x, mesh.y, v, cmap="RdBu_r", vmin=mid - lim, vmax=mid + lim
        )
        fig.colorbar(im, ax=ax, shrink=0.85)
        for unit in model.spec.units:
            for _, p, q in edges(unit.region, mesh.box):
                ax.plot([p[0], q[0]], [p[1], q[1]], "k--", lw=0.8)
        for fr in f.fractures:
            slip = fr.state == SLIP
            ax.plot(fr.points[:, 0], fr.points[:, 1], "-", color="0.3", lw=1.0)
            ax.plot(fr.points[slip, 0], fr.points[slip, 1], ".", color="orange", ms=3)
        ax.set_aspect("equal")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("x [m]")
    axes[0].set_ylabel("y [m]")
    fig.suptitle(
        f"{model.spec.name}: pore-pressure change "
        f"{result.load_factor * model.pore.change / 1e6:.3g} MPa "
        "(orange: slipping contact points)",
        fontsize=10,
    )
    path = out_dir / "depletion_field.png"
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
