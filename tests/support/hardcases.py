"""Inputs whose cost must follow the mesh, not their number of vertices, a
child process measured for its peak memory, and a case's memory estimates:
shared by tests/unit/geometry/test_hard_inputs.py, tests/unit/test_memory.py
and benchmarks/hard_inputs.py, benchmarks/memory_estimate.py."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from xfemslip.case import build

STRESS = {"xx": -20.0e6, "yy": -40.0e6, "xy": 0.0}


def _case(name, n, *, fractures=(), initial_stress=None, steps=1, **tables) -> str:
    """A 1 m square on n x n cells under STRESS, bottom on rollers, with the
    given fracture polylines and extra tables."""
    return build.case_text(
        {
            "name": name,
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [n, n]},
            "material": {"E": 5.0e9, "nu": 0.3},
            **tables,
            "fractures": [
                {"points": p, "friction": 0.1, "kn": 5.0e12, "kt": 5.0e12}
                for p in fractures
            ]
            or None,
            "loading": {
                "initial_stress": initial_stress,
                "stress": STRESS,
                "steps": steps,
            },
            "boundary": {
                "bottom": {"uy": 0.0},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
        }
    )


def zigzag(n_points=1000, n=20) -> str:
    """A polyline zigzagging inside the cell [0.45, 0.5]^2 of a 20 x 20 mesh."""
    xy = [
        [0.452 + 0.046 * i / (n_points - 1), 0.47 if i % 2 == 0 else 0.48]
        for i in range(n_points)
    ]
    return _case("zigzag", n, fractures=[xy])


def arc(n_points=2000, n=50) -> str:
    """A smooth arc of radius 0.5 about (0.5, 0.1) from 135 to 45 degrees."""
    xy = []
    for i in range(n_points):
        a = math.radians(135.0 - 90.0 * i / (n_points - 1))
        xy.append([0.5 + 0.5 * math.cos(a), 0.1 + 0.5 * math.sin(a)])
    return _case("arc", n, fractures=[xy])


def polygon(n_vertices=5000, n=50) -> str:
    """A reservoir bounded by a 5,000-vertex circle, depleted by 10 MPa."""
    ring = [
        [
            0.5 + 0.35 * math.cos(2 * math.pi * i / n_vertices),
            0.5 + 0.35 * math.sin(2 * math.pi * i / n_vertices),
        ]
        for i in range(n_vertices)
    ]
    return _case(
        "polygon",
        n,
        fractures=[[[0.35, 0.35], [0.65, 0.65]]],
        initial_stress=STRESS,
        steps=2,
        reservoir={"polygon": ring, "E": 5.0e9, "nu": 0.3},
        pore_pressure={"initial": 20.0e6, "change": -10.0e6, "region": "reservoir"},
    )


def depletion(n=20, change=-20.0e6) -> str:
    """The shipped depleting reservoir scaled to 1 m: a soft layer between
    rollers depleted by 20 MPa (``change`` [Pa]) in 10 steps, one fracture
    dipping 60 degrees in it (it first slips near dp = -12 MPa)."""
    stress = {"xx": -44.0e6, "yy": -62.0e6, "xy": 0.0}
    return build.case_text(
        {
            "name": "deplete",
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [n, n]},
            "material": {"E": 20.0e9, "nu": 0.25},
            "reservoir": {"box": [0.0, 0.4, 1.0, 0.6], "E": 8.0e9, "nu": 0.2},
            "pore_pressure": {
                "initial": 30.0e6,
                "change": change,
                "region": "reservoir",
            },
            "fractures": [
                {"center": [0.5, 0.5], "length": 0.15, "angle": 60.0, "friction": 0.5}
            ],
            "loading": {"initial_stress": stress, "stress": stress, "steps": 10},
            "boundary": {
                "left": {"ux": 0.0},
                "right": {"ux": 0.0},
                "bottom": {"uy": 0.0},
                "top": "traction",
            },
        }
    )


# Runs argv[2:] and writes its peak RSS [kB] to argv[1].  A process forked
# from a large one (pytest) starts with the parent's resident size as its
# ru_maxrss; forked from this small interpreter, the command's own peak is
# what is measured.
_PEAK_WRAPPER = """
import resource, subprocess, sys
code = subprocess.run(sys.argv[2:]).returncode
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
open(sys.argv[1], "w").write(str(peak))
sys.exit(code if code >= 0 else 128 - code)
"""


def measure(argv, timeout, log) -> tuple[int | str, float, float, list[str]]:
    """(exit code or 'timeout', wall [s], peak RSS [MB], output lines) of a
    command killed after ``timeout`` s; stdout and stderr go to the file
    ``log``, the peak to ``log`` + '.peak'."""
    # The peak comes from getrusage in a wrapper around the command, not
    # from psutil (not a dependency): psutil reads a process's current
    # resident memory while it runs, not its peak after it has exited.
    peak_file = f"{log}.peak"
    wrapped = [sys.executable, "-c", _PEAK_WRAPPER, peak_file, *argv]
    start = time.perf_counter()
    with open(log, "w+") as out:
        proc = subprocess.Popen(
            wrapped, stdout=out, stderr=subprocess.STDOUT, start_new_session=True
        )
        try:
            code = proc.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            code = "timeout"
        wall = time.perf_counter() - start
        out.seek(0)
        lines = [line for line in out.read().splitlines() if line.strip()]
    peak = math.nan if code == "timeout" else float(Path(peak_file).read_text()) / 1024
    return code, wall, peak, lines


def estimates(path) -> list[float]:
    """The three memory estimates [B] of a case file (xfemslip.memory: from
    the case, after the node enrichments, from the built model), with no
    limit applied."""
    from xfemslip import memory
    from xfemslip.case import load_case
    from xfemslip.fem.enrichment import find_candidates
    from xfemslip.fem.mesh import build_mesh
    from xfemslip.geometry.junctions import build_fractures
    from xfemslip.simulation import build_model

    spec = load_case(path)
    out = [memory.estimate_terms(memory.case_footprint(spec))["total"]]
    mesh = build_mesh(spec.mesh.x, spec.mesh.y)
    box = [mesh.x[0], mesh.x[-1], mesh.y[0], mesh.y[-1]]
    fractures = build_fractures(mesh, spec.fractures, box)
    cand = find_candidates(mesh, fractures)
    fp = memory.enriched_footprint(spec, mesh, fractures, cand)
    out.append(memory.estimate_terms(fp)["total"])
    model = build_model(spec)
    out.append(memory.estimate_terms(memory.model_footprint(model))["total"])
    return out
