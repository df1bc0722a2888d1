"""Aperture, transmissivity and the block's permeability tensor against hand
computations.

1. A unit block fully cut by a horizontal fault at y = 0.53, bottom edge
   fixed, top edge moved by ux = d under a normal compression P, friction 0
   and nu = 0: the top block translates rigidly (no shear crosses the fault,
   no Poisson expansion bends it), so the slip is d and sigma_n = -P at every
   contact point.  The aperture law then gives by hand

       a = a0 + min(d, s_max) tan(psi) - [c(P) - c(P0)],
       c(p) = V_m p / (K_ni V_m + p),

   (P0 the in-situ compression, 0 or 4 MPa; the penalty's elastic normal
   jump is no opening), T = a^3 / 12, and the fault, of length 1 across the block,
   k_xx = a^3 L / (12 A) + k_m, k_yy = k_m, k_xy = 0 (Oda, straight
   fracture along x), for the whole domain and for a sub-block that cuts
   the fault mid-element.
2. The inclined crack of the in-situ release problem (a = 1 m at 45 degrees
   in an 80 m box): in situ every aperture is a0, so the tensor is the
   closed form a0^3 L t t^T / (12 A) + k_m I with t = (1, 1) / sqrt(2), over
   the domain (L = 2a) and over a block holding half the crack (L = a).
3. One-way coupling: the mechanical datasets of result.h5 are the same bytes
   with and without [permeability].
"""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
import tomli_w

import xfemslip
from tests.support.harness import case_text
from tests.support.in_situ import HALF, SIGMA0, A, crack_case, rollers
from xfemslip.case import load_case
from xfemslip.simulation import run_case

pytestmark = pytest.mark.verification

Y0, P, P0, D = 0.53, 10.0e6, 4.0e6, 2.0e-3
A0, PSI, VM, KNI, KM = 1.0e-4, 10.0, 5.0e-5, 1.0e11, 1.0e-18


def _closure(p: float) -> float:
    return VM * p / (KNI * VM + p)


def _block_case(tmp_path, s_max, initial, block=None):
    law = {
        "aperture": A0,
        "dilation_angle": PSI,
        "max_closure": VM,
        "normal_stiffness": KNI,
        "matrix": KM,
    }
    if s_max is not None:
        law["dilation_slip"] = s_max
    if block is not None:
        law["block"] = block
    text = case_text(
        nu=0.0,
        fractures=[
            dict(
                points=[[0.0, Y0], [1.0, Y0]],
                friction=0.0,
                cohesion=0.0,
                kn=5.0e12,
                kt=5.0e12,
            )
        ],
        boundary={
            "bottom": {"ux": 0.0, "uy": 0.0},
            "top": {"ux": D, "traction": True},
            "left": "free",
            "right": "free",
        },
        stress=(0.0, -P, 0.0),
        initial_stress=(0.0, -P0, 0.0) if initial else None,
    )
    path = tmp_path / "block.toml"
    path.write_text(text + "[permeability]\n" + tomli_w.dumps(law))
    run_case(load_case(path), tmp_path / "out")
    return xfemslip.read_result(tmp_path / "out")


@pytest.mark.parametrize(
    ("s_max", "initial"),
    [(1.0e-3, False), (None, False), (1.0e-3, True)],
    ids=["capped", "uncapped", "in-situ-compressed"],
)
def test_uniform_slip_gives_the_hand_computed_aperture(tmp_path, s_max, initial):
    result = _block_case(tmp_path, s_max, initial)
    (ff,) = result.fractures
    # premise: uniform slip d and sigma_n = -P
    np.testing.assert_allclose(ff.slip, D, rtol=1e-9)
    np.testing.assert_allclose(ff.normal_traction, -P, rtol=1e-9)
    dilation = min(D, s_max or math.inf) * math.tan(math.radians(PSI))
    closure = _closure(P) - (_closure(P0) if initial else 0.0)
    a = A0 + dilation - closure
    np.testing.assert_allclose(ff.aperture, a, rtol=1e-9)
    np.testing.assert_allclose(ff.transmissivity, a**3 / 12.0, rtol=1e-9)
    k = result.permeability
    np.testing.assert_allclose(k.in_situ, [[A0**3 / 12 + KM, 0], [0, KM]], rtol=1e-12)
    np.testing.assert_allclose(
        k.tensors[-1], [[a**3 / 12 + KM, 0], [0, KM]], rtol=1e-9, atol=1e-30
    )
    ratio = (a**3 / 12 + KM) / (A0**3 / 12 + KM)
    np.testing.assert_allclose(k.ratio(), [ratio, 1.0], rtol=1e-9)


def test_a_sub_block_counts_the_fault_inside_it(tmp_path):
    """Block [0.25, 0.15, 0.75, 0.95]: L = 0.5 of the fault, A = 0.4 m^2."""
    result = _block_case(tmp_path, 1.0e-3, False, block=[0.25, 0.15, 0.75, 0.95])
    a = A0 + 1.0e-3 * math.tan(math.radians(PSI)) - _closure(P)
    k = result.permeability
    assert k.block == (0.25, 0.15, 0.75, 0.95)
    expected = a**3 * 0.5 / (12 * 0.4) + KM
    assert k.tensors[-1][0, 0] == pytest.approx(expected, rel=1e-9)
    assert k.in_situ[0, 0] == pytest.approx(A0**3 * 0.5 / (12 * 0.4) + KM, rel=1e-12)


@pytest.mark.parametrize(
    ("block", "length"),
    [(None, 2 * A), ([0.0, 0.0, HALF, HALF], A)],
    ids=["domain", "half-the-crack"],
)
def test_in_situ_tensor_of_an_inclined_crack_is_the_closed_form(
    tmp_path, block, length
):
    doc = crack_case(0.25, initial=SIGMA0, boundary=rollers())
    doc["permeability"] = {"aperture": A0, "matrix": KM}
    if block is not None:
        doc["permeability"]["block"] = block
    path = tmp_path / "crack.toml"
    path.write_text(tomli_w.dumps(doc))
    result = run_case(load_case(path))
    area = (2 * HALF) ** 2 if block is None else HALF**2
    t = np.array([1.0, 1.0]) / math.sqrt(2.0)
    exact = A0**3 * length * np.outer(t, t) / (12 * area) + KM * np.eye(2)
    np.testing.assert_allclose(result.permeability.in_situ, exact, rtol=1e-12)
    # without dilation or closure the released crack keeps a0 (it slips but
    # stays closed: its penalty normal jump is no opening)
    np.testing.assert_allclose(result.fractures[0].aperture, A0, rtol=1e-12)
    np.testing.assert_allclose(result.permeability.tensors[-1], exact, rtol=1e-12)


def test_permeability_leaves_the_mechanical_datasets_unchanged(tmp_path):
    """One-way coupling: every dataset of the file without [permeability] is
    in the file with it, with the same bytes; the new ones are the apertures,
    the transmissivities and /permeability."""
    doc = crack_case(0.25, initial=SIGMA0, boundary=rollers())
    doc["loading"]["steps"] = 2
    plain = tmp_path / "plain.toml"
    plain.write_text(tomli_w.dumps(doc))
    doc["permeability"] = {"aperture": A0, "dilation_angle": 5.0}
    hydraulic = tmp_path / "hydraulic.toml"
    hydraulic.write_text(tomli_w.dumps(doc))
    run_case(load_case(plain), tmp_path / "a")
    run_case(load_case(hydraulic), tmp_path / "b")

    def datasets(path):
        out = {}
        with h5py.File(path, "r") as h5:
            h5.visititems(
                lambda name, item: (
                    out.__setitem__(name, item[()].tobytes())
                    if isinstance(item, h5py.Dataset)
                    else None
                )
            )
        return out

    a, b = datasets(tmp_path / "a/result.h5"), datasets(tmp_path / "b/result.h5")
    assert all(b[name] == value for name, value in a.items())
    added = {name.rsplit("/", 1)[-1] for name in set(b) - set(a)}
    assert added == {
        "aperture",
        "transmissivity",
        "step",
        "in_situ",
        "tensor",
        "initial_aperture",
    }
    assert not any(name.startswith("permeability") for name in a)
