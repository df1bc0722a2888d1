"""The displaced-fault benchmark (cases/displaced_fault.toml) held stuck,
against the inclusion closed form (xfemslip.reference.inclusion)."""

from __future__ import annotations

import math

import numpy as np

from tests.support.golden import ROOT
from xfemslip.case import build, loads_case
from xfemslip.reference.inclusion import displaced_fault, fault_tractions
from xfemslip.simulation import build_model, newton_solver

CASE = ROOT / "cases" / "displaced_fault.toml"
HEIGHT, THROW, DIP, NU, ALPHA, DP = 225.0, 75.0, 70.0, 0.15, 0.9, -25.0e6


def stuck_fault_errors(size: float) -> dict:
    """Per traction (shear, normal): the largest and the rms error of the
    contact patches' traction changes against the patch means of the closed
    form, relative to the largest closed-form value, over the patches farther
    than 0.05 H from the four corners (log singularities)."""
    keys = {
        "mesh.size": size,
        "fractures.0.cohesion": 1.0e9,
        "loading.steps": 1,
        "output.formats": ["h5"],
    }
    spec = loads_case(build.case_text(build.file_case(CASE, **keys)), CASE)
    model = build_model(spec)
    solver = newton_solver(model)
    solver.run(1)
    res, ip, cs = solver.completed[-1].contact, model.ip, model.contact
    assert np.all(res.state == 1), "the fault must stay stuck"
    fault = displaced_fault(HEIGHT, THROW, DIP)
    ref = fault_tractions(fault, ip.xy[:, 1], DP, DP, NU, ALPHA)
    t = cs.tangent[0]
    W = np.bincount(cs.patch, weights=ip.weight)
    yc = np.bincount(cs.patch, weights=ip.weight * ip.xy[:, 1]) / W
    half = 0.5 * W * abs(t[1])
    dist = np.min(np.abs(yc[:, None] - fault.corners[None, :]), axis=1) - half
    keep = dist > 0.05 * HEIGHT
    out = {"h": size, "patches": int(keep.sum())}
    pn0, pt0 = cs.pn0, -cs.kt * cs.slip_reference
    # the contact law acts on the effective normal traction, whose change is
    # that of the total one plus the fault's fluid pressure change
    dpf = model.pore.fluid(1.0) - model.pore.fluid(0.0)
    dpf_patch = np.bincount(cs.patch, weights=ip.weight * dpf) / W
    for name, got, want in (
        ("shear", res.pt - pt0, ref.tau),
        ("normal", res.pn - pn0 - dpf_patch, ref.sigma_n),
    ):
        finite = np.isfinite(want)
        mean = np.bincount(cs.patch, weights=np.where(finite, ip.weight * want, 0)) / W
        err = got[keep] - mean[keep]
        scale = np.max(np.abs(mean[keep]))
        out[name] = (
            float(np.max(np.abs(err)) / scale),
            float(math.sqrt(np.mean(err**2)) / scale),
        )
    return out
