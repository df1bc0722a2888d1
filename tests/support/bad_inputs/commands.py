"""Command families of the bad-input suite: command-line options,
environment variables, sizes, and geometry of many vertices."""

from __future__ import annotations

import copy
import math

from tests.support.bad_inputs.base import (
    DEPLETION,
    OUT,
    RUN,
    SMALL,
    Input,
    Special,
    _lazy,
    network_case,
    small,
    toml,
)

# --------------------------------------------------------------------------- #
# Command line, environment, sizes
# --------------------------------------------------------------------------- #


def _empty_h5() -> bytes:
    """A valid HDF5 file that holds nothing."""
    import io

    import h5py

    buffer = io.BytesIO()
    with h5py.File(buffer, "w"):
        pass
    return buffer.getvalue()


def cli_inputs() -> list[Input]:
    case = {
        "case.toml": toml(small()),
        "file.txt": "x",
        "fake.h5": "not HDF5\n",
        "empty.h5": Special("lazy", _empty_h5),
        "summary.csv": "status,slipping_fractures,fractures\nok,x,3\n",
        "pipe": Special("fifo"),
    }
    long_part = "p" * 300
    deep = "/".join(["d"] * 2100)
    lines = {
        "run-no-case": (("run",), ("CASE",)),
        "run-two-cases": (("run", "case.toml", "case.toml"), ()),
        "run-unknown-option": (("run", "--bogus", "case.toml"), ("--bogus",)),
        "run-missing-file": (("run", "nope.toml", "-o", OUT), ("nope.toml",)),
        "run-case-is-dir": (("run", ".", "-o", OUT), ()),
        "run-o-is-file": (("run", "case.toml", "-o", "file.txt"), ("--output",)),
        "run-o-nul": (("run", "case.toml", "-o", "a\0b"), ("--output",)),
        "run-o-long-part": (("run", "case.toml", "-o", long_part), ("--output",)),
        "run-o-long-path": (("run", "case.toml", "-o", deep), ("--output",)),
        "run-o-empty": (("run", "case.toml", "-o", ""), ()),
        "run-case-nul": (("run", "ca\0se.toml", "-o", OUT), ()),
        "run-case-long": (("run", long_part + ".toml", "-o", OUT), ()),
        "run-verbose-quiet": (("run", "-v", "-q", "case.toml", "-o", OUT), ()),
        "check-no-case": (("check",), ("CASE",)),
        "unknown-command": (("frobnicate",), ("frobnicate",)),
        "info-extra": (("info", "extra"), ()),
        "sweep-jobs-0": (("sweep", "-j", "0", "case.toml"), ("--jobs",)),
        "sweep-jobs-text": (("sweep", "-j", "many", "case.toml"), ("--jobs",)),
        "sweep-jobs-huge": (("sweep", "-j", "1" + "0" * 30, "case.toml"), ("--jobs",)),
        "sweep-jobs-1000": (("sweep", "-j", "1000", "case.toml"), ("--jobs",)),
        "sweep-missing": (("sweep", "nope.toml", "-o", OUT), ("nope.toml",)),
        "sweep-o-nul": (("sweep", "case.toml", "-o", "a\0b"), ("--output",)),
        "plot-missing": (("plot", "nope.h5", "-o", OUT), ()),
        "plot-fake-h5": (("plot", "fake.h5", "-o", OUT), ("fake.h5",)),
        "plot-empty-h5": (("plot", "empty.h5", "-o", OUT), ("empty.h5",)),
        "plot-dev-zero": (("plot", "/dev/zero", "-o", OUT), ("/dev/zero",)),
        "plot-dpi-1e9": (("plot", "empty.h5", "--dpi", "1e9", "-o", OUT), ("--dpi",)),
        "plot-scale-inf": (("plot", "empty.h5", "--scale", "inf", "-o", OUT), ()),
        "dfn-summary-dev-zero": (
            ("dfn", "case.toml", "--plot", "n.png", "--summary", "/dev/zero"),
            ("/dev/zero",),
        ),
        "dfn-summary-fifo": (
            ("dfn", "case.toml", "--plot", "n.png", "--summary", "pipe"),
            ("pipe",),
        ),
        "dfn-summary-not-integers": (
            ("dfn", "case.toml", "--plot", "n.png", "--summary", "summary.csv"),
            ("summary.csv line 2",),
        ),
        "dfn-result-fake": (
            ("dfn", "case.toml", "--plot", "n.png", "--result", "fake.h5"),
            ("fake.h5",),
        ),
        "dfn-result-empty": (
            ("dfn", "case.toml", "--plot", "n.png", "--result", "empty.h5"),
            ("empty.h5",),
        ),
        "plot-not-h5": (("plot", "file.txt", "-o", OUT), ()),
        "plot-case-as-result": (("plot", "case.toml", "-o", OUT), ()),
        "plot-dpi-0": (("plot", "file.txt", "--dpi", "0", "-o", OUT), ("--dpi",)),
        "plot-figure-bad": (("plot", "file.txt", "--figure", "x", "-o", OUT), ()),
        "screen-no-input": (("screen",), ()),
        "screen-stress-nan": (
            ("screen", "--stress", "nan", "1", "0", "--friction", "0.5"),
            (),
        ),
        "screen-stress-arity": (("screen", "--stress", "1", "2"), ()),
        "screen-step-0": (
            ("screen", "--stress", "-1", "-2", "0", "--friction", "0.5", "--step", "0"),
            ("--step",),
        ),
        "screen-step-1e-300": (
            (
                "screen",
                "--stress",
                "-1",
                "-2",
                "0",
                "--friction",
                "0.5",
                "--step",
                "1e-300",
            ),
            ("--step",),
        ),
        "screen-friction-negative": (
            ("screen", "--stress", "-1", "-2", "0", "--friction", "-1"),
            ("--friction",),
        ),
        "dfn-csv-into-missing-dir": (
            ("dfn", "case.toml", "--csv", "no/such/dir/x.csv"),
            (),
        ),
        "dfn-plot-bad-suffix": (("dfn", "case.toml", "--plot", "net.xyz"), ()),
        "deplete-no-case": (("deplete",), ("CASE",)),
        "verify-penalty-text": (("verify", "--quick", "--penalty", "abc"), ()),
    }
    out = []
    for name, (argv, names) in lines.items():
        expect = {2}
        if name in ("dfn-csv-into-missing-dir",):
            expect = {1, 2}
        out.append(
            Input(
                id=f"cli/{name}",
                family="cli",
                files=dict(case),
                argv=argv,
                expect=frozenset(expect),
                names=names,
            )
        )
    return out


def environment_inputs() -> list[Input]:
    """Bad values of the variables xfemslip and Numba read: the memory limit
    and the kernel choice in-process, Numba's (read once, at import) in a
    fresh interpreter."""
    case = {"case.toml": toml(small())}
    runs = (*RUN, "case.toml", "-o", OUT)
    out = []
    for value in ("0", "-5", "abc", "nan", "inf", "1e400", "10Q", "5 G", "", " "):
        expect = {0} if value in ("", " ", "5 G") else {2}
        out.append(
            Input(
                id=f"env/XFEMSLIP_MEMORY_LIMIT={value!r}",
                family="environment",
                files=dict(case),
                argv=runs,
                env={"XFEMSLIP_MEMORY_LIMIT": value},
                expect=frozenset(expect),
                names=("XFEMSLIP_MEMORY_LIMIT",) if expect == {2} else (),
            )
        )
    out.append(
        Input(
            id="env/XFEMSLIP_MEMORY_LIMIT=1k",
            family="environment",
            files=dict(case),
            argv=runs,
            env={"XFEMSLIP_MEMORY_LIMIT": "1k"},
            names=("mesh", "XFEMSLIP_MEMORY_LIMIT"),
        )
    )
    for value, expect in (
        ("fortran", {2}),
        ("NUMBA", {0}),
        (" numpy ", {0}),
        ("", {0}),
    ):
        out.append(
            Input(
                id=f"env/XFEMSLIP_KERNELS={value!r}",
                family="environment",
                files=dict(case),
                argv=runs,
                env={"XFEMSLIP_KERNELS": value},
                expect=frozenset(expect),
                names=("XFEMSLIP_KERNELS",) if expect == {2} else (),
            )
        )
    numba_case = {"case.toml": toml(small(solver={"kernels": "numba"}))}
    for name, value in (
        ("NUMBA_NUM_THREADS", "0"),
        ("NUMBA_NUM_THREADS", "-1"),
        ("NUMBA_NUM_THREADS", "abc"),
        ("NUMBA_NUM_THREADS", "1.5"),
        ("NUMBA_DISABLE_JIT", "yes"),
    ):
        out.extend(
            Input(
                id=f"env/{name}={value}/{argv[0]}",
                family="environment",
                files=dict(numba_case),
                argv=argv,
                env={name: value},
                names=(name,),
                subprocess=True,
                timeout=120.0,
            )
            for argv in (("info",), runs)
        )
    out.append(
        Input(
            id="env/NUMBA_NUM_THREADS=1/run",
            family="environment",
            files=dict(numba_case),
            argv=runs,
            env={"NUMBA_NUM_THREADS": "1"},
            expect=frozenset({0}),
            subprocess=True,
            timeout=120.0,
        )
    )
    return out


def size_inputs() -> list[Input]:
    """Sizes that must be refused before anything of that size is allocated."""
    docs = {
        "elements-1e9x1e9": (small(mesh={"elements": [10**9, 10**9]}), ("mesh",)),
        "elements-2**63": (small(mesh={"elements": [2**63 - 1, 1]}), ("mesh",)),
        "elements-0": (small(mesh={"elements": [0, 4]}), ("mesh.elements",)),
        "elements-float": (small(mesh={"elements": [4.0, 4]}), ("mesh.elements",)),
        "elements-3": (small(mesh={"elements": [4, 4, 4]}), ("mesh.elements",)),
        "elements-memory": (small(mesh={"elements": [20000, 20000]}), ("mesh",)),
        # at the element-count limit: the memory estimate refuses it (4 GB)
        "elements-5000x5000": (small(mesh={"elements": [5000, 5000]}), ("mesh",)),
        "x-not-increasing": (
            small(mesh={"x": [0.0, 0.5, 0.4, 1.0], "y": [0.0, 0.5, 1.0]}),
            ("mesh.x",),
        ),
        "x-100k-nodes": (
            small(mesh={"x": [i / 100_000 for i in range(100_001)], "y": [0.0, 1.0]}),
            (),
        ),
        "steps-0": (
            small(loading=dict(SMALL["loading"], steps=0)),
            ("loading.steps",),
        ),
        "steps-1e6": (
            small(loading=dict(SMALL["loading"], steps=10**6)),
            ("loading.steps",),
        ),
        "fractures-0-points": (
            small(fractures=[dict(SMALL["fractures"][0], points=[])]),
            ("fractures[0].points",),
        ),
        "fractures-1-point": (
            small(fractures=[dict(SMALL["fractures"][0], points=[[0.5, 0.5]])]),
            ("fractures[0].points",),
        ),
        "fracture-3d-point": (
            small(
                fractures=[
                    dict(SMALL["fractures"][0], points=[[0.2, 0.2, 0], [0.8, 0.8]])
                ]
            ),
            ("fractures[0].points",),
        ),
        "5000-fractures": (
            small(
                fractures=[
                    dict(
                        SMALL["fractures"][0],
                        points=[[0.1, 0.1 + i * 1.6e-4], [0.9, 0.1 + i * 1.6e-4]],
                    )
                    for i in range(5000)
                ]
            ),
            (),
        ),
        "polygon-3-collinear": (
            small(
                reservoir={"polygon": [[0, 0], [0.5, 0.5], [1, 1]], "E": 1e9, "nu": 0.2}
            ),
            ("reservoir.polygon",),
        ),
        "formats-duplicate": (
            small(output={"formats": ["h5", "h5"]}),
            ("output.formats",),
        ),
        "formats-empty": (small(output={"formats": []}), ("output.formats",)),
        "name-dot": (small(name=".."), ("name",)),
        "name-single-dot": (small(name="."), ("name",)),
        "name-nul": (small(name="a\0b"), ("name",)),
        "name-300": (small(name="n" * 300), ("name",)),
        "name-unicode-200": (small(name="\u00e9" * 200), ("name",)),
        "dir-nul": (
            small(output={"directory": "o\0ut", "formats": ["h5"]}),
            ("output.directory",),
        ),
        "dir-long-part": (
            small(output={"directory": "d" * 256, "formats": ["h5"]}),
            ("output.directory",),
        ),
        "dir-long-path": (
            small(output={"directory": "/".join(["d"] * 2100), "formats": ["h5"]}),
            ("output.directory",),
        ),
    }
    out = []
    for name, (doc, names) in docs.items():
        refused = bool(names)
        argv = (
            (*RUN, "case.toml")
            if "name" in name or "dir-" in name
            else (*RUN, "case.toml", "-o", OUT)
        )
        out.append(
            Input(
                id=f"sizes/{name}",
                family="sizes",
                files={"case.toml": toml(doc)},
                argv=argv,
                env={"XFEMSLIP_MEMORY_LIMIT": "4G"},
                expect=frozenset({2}) if refused else frozenset({0, 1, 2}),
                names=("case.toml", *names),
                out=OUT if "-o" in argv else None,
                timeout=60.0,
            )
        )
    return out


# A run of these takes seconds once the geometry is simplified below the mesh
# resolution; walked point by point it takes minutes.  The bound leaves room
# for a loaded machine.
SHAPE_TIMEOUT = 60.0


def shape_inputs() -> list[Input]:
    """Geometry with many vertices: it must be simplified (with a warning),
    refused or run -- within the time bound, not walked point by point."""
    out = []

    def zigzag(n):
        return [[0.42 + 0.06 * (i % 2), 0.42 + 0.06 * i / n] for i in range(n)]

    def arc(n):
        t = [math.pi * i / (n - 1) for i in range(n)]
        return [[0.5 + 0.3 * math.cos(a), 0.5 + 0.3 * math.sin(a)] for a in t]

    def polygon(n):
        t = [2 * math.pi * i / n for i in range(n)]
        return [[0.5 + 0.25 * math.cos(a), 0.5 + 0.2 * math.sin(a)] for a in t]

    for name, points, cells in (
        ("zigzag-40-in-one-cell", zigzag(40), 10),
        ("zigzag-1000-in-one-cell", zigzag(1000), 10),
        ("arc-200", arc(200), 20),
        ("arc-2000", arc(2000), 50),
    ):
        doc = small(mesh={"elements": [cells, cells]})
        doc["fractures"][0]["points"] = points
        out.append(
            Input(
                id=f"shapes/{name}",
                family="shapes",
                files={"case.toml": toml(doc)},
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset({0, 1, 2}),
                timeout=SHAPE_TIMEOUT,
            )
        )

    def trace(n):  # a digitised fault trace: one fracture of n segments
        p = [
            (0.1 + 0.8 * i / n, 0.5 + 0.01 * math.sin(40 * i / n)) for i in range(n + 1)
        ]
        return "fracture,x0,y0,x1,y1\n" + "".join(
            f"a,{p[i][0]!r},{p[i][1]!r},{p[i + 1][0]!r},{p[i + 1][1]!r}\n"
            for i in range(n)
        )

    out.append(
        Input(
            id="shapes/network-csv-trace-20000",
            family="shapes",
            files={
                "case.toml": toml(network_case(file="net.csv")),
                "net.csv": _lazy(lambda: trace(20_000)),
            },
            argv=("check", "case.toml"),
            expect=frozenset({0, 2}),
            out=None,
            timeout=SHAPE_TIMEOUT,
        )
    )
    for n in (300, 5000):
        doc = copy.deepcopy(DEPLETION)
        doc["mesh"] = {"elements": [10, 10]}
        doc["reservoir"] = {"polygon": polygon(n), "E": 5.0e8, "nu": 0.2}
        doc["pore_pressure"]["region"] = "reservoir"
        out.append(
            Input(
                id=f"shapes/reservoir-polygon-{n}",
                family="shapes",
                files={"case.toml": toml(doc)},
                argv=(*RUN, "case.toml", "-o", OUT),
                expect=frozenset({0, 1, 2}),
                timeout=SHAPE_TIMEOUT,
            )
        )
    out.append(
        Input(
            id="shapes/deplete-tolerance-1e-10",
            family="shapes",
            files={"case.toml": toml(DEPLETION)},
            argv=("deplete", "-q", "case.toml", "-o", OUT, "--tolerance", "1e-10"),
            expect=frozenset({0, 1, 2}),
            timeout=SHAPE_TIMEOUT,
        )
    )
    return out
