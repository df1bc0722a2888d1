"""Figure of an uncertainty study: probability of slip against depletion.

Imported only when plotting (matplotlib is not a dependency of a run).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_probability(result, path: Path, dpi: float = 110.0) -> Path:
    """P that each fracture has slipped against the pore-pressure change [MPa],
    with its Wilson band; written to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spec = result.spec
    levels = np.asarray(spec.levels, float)
    depletion = levels[-1] < 0.0
    x = (-levels if depletion else levels) / 1e6
    fig, ax = plt.subplots(figsize=(6.4, 4.2), constrained_layout=True)
    colours = plt.get_cmap("tab10" if len(result.fractures) <= 10 else "tab20")
    for j, fi in enumerate(result.fractures):
        colour = colours(j % colours.N)
        ax.fill_between(
            x, result.ci_low[j], result.ci_high[j], color=colour, alpha=0.2, lw=0
        )
        ax.plot(
            x, result.probability[j], "o-", ms=3, color=colour, label=f"fracture {fi}"
        )
    ax.set_xlabel(
        "pore-pressure drop $-\\Delta p$ [MPa]"
        if depletion
        else "pore-pressure change $\\Delta p$ [MPa]"
    )
    ax.set_ylabel("probability of slip")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlim(min(x.min(), 0.0), x.max())
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    base = spec.base_spec.name
    ax.set_title(
        f"{base}: {result.evaluated} samples ({spec.evaluate}), "
        f"{spec.confidence:.0%} Wilson bands",
        fontsize="medium",
    )
    fig.savefig(path, dpi=dpi, format="png")
    plt.close(fig)
    return Path(path)
