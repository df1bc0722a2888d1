"""Edge families of the bad-input suite: distributions of uncertainty studies
at their edges, every post-processing key of a case at its bounds
(``[permeability]``, ``hydraulic``, ``[events]``), the summary CSV of
``dfn --summary``, and cases read from standard input.

Each value sits on, just inside or far beyond the bound the case or sweep
format gives it (docs/case-format.md, docs/sweep-format.md): inside, the
command runs and every number it writes is finite; beyond, one line names
the key (exit 2) and nothing is written.
"""

from __future__ import annotations

import copy

from tests.support.bad_inputs.base import (
    DEPLETION,
    GENERATE,
    OUT,
    Input,
    network_case,
    toml,
)

# --------------------------------------------------------------------------- #
# Uncertainty: distributions at their edges
# --------------------------------------------------------------------------- #

SCREEN = 'samples = 40\nseed = 1\nevaluate = "screen"\nlevels = [0.0, -5.0e5, -1.0e6]'
XFEM = 'samples = 3\nseed = 1\nevaluate = "xfem"\nlevels = [0.0, -5.0e5, -1.0e6]'


def _sweep(head: str, inputs: str, base: str = "base.toml") -> str:
    return (
        f'name = "un"\nbase = "{base}"\n\n[uncertainty]\n{head}\n'
        f"\n[uncertainty.inputs]\n{inputs}\n"
    )


def _input(key: str, table: str) -> str:
    return f'"{key}" = {table}'


FRICTION = '"fractures[0].friction"'


def uncertainty_edge_inputs() -> list[Input]:
    """[uncertainty] files whose distributions overflow, leave what the case
    format allows, hold extreme weights, or whose study is degenerate."""
    ok, refused, partly = frozenset({0}), frozenset({2}), frozenset({1})
    cases = {
        # draws that overflow: refused at the key
        "uniform-1e308": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "uniform", low = -1e308, high = 1e308 }}',
            refused,
        ),
        "uniform-stress-1e308": (
            SCREEN,
            _input(
                "loading.initial_stress.xx",
                '{ distribution = "uniform", low = -1e308, high = 1e308 }',
            ),
            refused,
        ),
        "triangular-1e308": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "triangular", low = -1e308, '
            "mode = 0.0, high = 1e308 }",
            refused,
        ),
        "lognormal-sigma-1000": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "lognormal", median = 0.5, '
            "sigma = 1000.0 }",
            refused,
        ),
        "normal-std-1e308": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "normal", mean = 0.5, std = 1e308 }}',
            refused,
        ),
        # wide but finite: runs, samples outside refused one by one
        "lognormal-sigma-30": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "lognormal", median = 0.5, '
            "sigma = 30.0 }",
            frozenset({0, 1}),
        ),
        # outside what the case format allows
        "nu-normal-partly-negative": (
            SCREEN,
            _input("material.nu", '{ distribution = "normal", mean = 0.1, std = 0.2 }'),
            partly,
        ),
        "nu-normal-partly-negative-xfem": (
            XFEM,
            _input(
                "material.nu",
                '{ distribution = "uniform", low = -0.3, high = 0.3 }',
            ),
            frozenset({0, 1}),
        ),
        "nu-all-negative": (
            SCREEN,
            _input(
                "material.nu", '{ distribution = "uniform", low = -0.4, high = -0.1 }'
            ),
            refused,
        ),
        "nu-all-negative-xfem": (
            XFEM,
            _input(
                "material.nu", '{ distribution = "uniform", low = -0.4, high = -0.1 }'
            ),
            refused,
        ),
        "nu-truncated-inside": (
            SCREEN,
            _input(
                "material.nu",
                '{ distribution = "normal", mean = 0.1, std = 0.2, low = 0.0, '
                "high = 0.45 }",
            ),
            ok,
        ),
        "E-negative": (
            SCREEN,
            _input(
                "material.E", '{ distribution = "uniform", low = -2e9, high = -1e9 }'
            ),
            refused,
        ),
        "friction-normal-partly-negative": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "normal", mean = 0.1, std = 0.2 }}',
            partly,
        ),
        "friction-choice-negative": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "choice", values = [-0.2, -0.1] }}',
            refused,
        ),
        "biot-above-1": (
            SCREEN,
            _input(
                "pore_pressure.biot",
                '{ distribution = "uniform", low = 1.5, high = 2.0 }',
            ),
            refused,
        ),
        # extreme weights: normalised by the largest
        "choice-weights-1e308": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "choice", values = [0.3, 0.5, 0.7], '
            "weights = [1e308, 1e308, 1e308] }",
            ok,
        ),
        "choice-weights-1e308-and-0": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "choice", values = [0.3, 0.5], '
            "weights = [1e308, 0.0] }",
            ok,
        ),
        "choice-weights-subnormal": (
            SCREEN,
            f'{FRICTION} = {{ distribution = "choice", values = [0.3, 0.5], '
            "weights = [5e-324, 5e-324] }",
            ok,
        ),
        # targets and sizes
        "half-width-1e-9": (
            SCREEN + "\nhalf_width = 1e-9",
            f'{FRICTION} = {{ distribution = "uniform", low = 0.3, high = 0.7 }}',
            refused,
        ),
        "half-width-subnormal": (
            SCREEN + "\nhalf_width = 5e-324",
            f'{FRICTION} = {{ distribution = "uniform", low = 0.3, high = 0.7 }}',
            refused,
        ),
        "confidence-near-1": (
            SCREEN + "\nconfidence = 0.999999999999\nhalf_width = 0.002",
            f'{FRICTION} = {{ distribution = "uniform", low = 0.3, high = 0.7 }}',
            refused,
        ),
        "samples-1": (
            SCREEN.replace("samples = 40", "samples = 1"),
            f'{FRICTION} = {{ distribution = "uniform", low = 0.3, high = 0.7 }}',
            ok,
        ),
        "samples-1-xfem": (
            XFEM.replace("samples = 3", "samples = 1"),
            f'{FRICTION} = {{ distribution = "uniform", low = 0.3, high = 0.7 }}',
            ok,
        ),
    }
    base = toml(DEPLETION)
    no_fracture = copy.deepcopy(DEPLETION)
    del no_fracture["fractures"]
    out = []
    for name, (head, inputs, expect) in cases.items():
        out.append(
            Input(
                id=f"uncertainty-edge/{name}",
                family="uncertainty-edges",
                files={"sweep.toml": _sweep(head, inputs), "base.toml": base},
                argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
                expect=expect,
                names=("sweep.toml", "uncertainty") if expect == refused else (),
                timeout=60.0,
            )
        )
    for evaluate, head in (("screen", SCREEN), ("xfem", XFEM)):
        out.append(
            Input(
                id=f"uncertainty-edge/no-fracture-{evaluate}",
                family="uncertainty-edges",
                files={
                    "sweep.toml": _sweep(
                        head,
                        _input(
                            "material.E",
                            '{ distribution = "uniform", low = 0.9e9, high = 1.1e9 }',
                        ),
                    ),
                    "base.toml": toml(no_fracture),
                },
                argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
                names=("sweep.toml", "base"),
            )
        )
    return out


# --------------------------------------------------------------------------- #
# Post-processing keys of a case at their bounds
# --------------------------------------------------------------------------- #


def _post_case(permeability=None, events=None, hydraulic=None, initial=True) -> dict:
    doc = copy.deepcopy(DEPLETION)
    if permeability is not None:
        doc["permeability"] = permeability
    if events is not None:
        doc["events"] = events
    if hydraulic is not None:
        doc["fractures"][0]["hydraulic"] = hydraulic
    if not initial:  # no in-situ state: sigma_n0' = p0
        del doc["loading"]["initial_stress"]
        doc["pore_pressure"]["initial"] = 0.0
    return doc


A0 = 1.0e-4
CELL = 1.0 / 6.0  # the cell of DEPLETION's 6 x 6 mesh of the unit square


def post_key_inputs() -> list[Input]:
    """Every key of [permeability], a fracture's hydraulic table and [events]
    at and beyond its bounds, through ``run`` (which ends with the summary
    and writes result.h5: every number of both must be finite)."""
    run, refused = frozenset({0, 1}), frozenset({2})
    K = {"normal_stiffness": 1.0e10}
    cases = {
        "aperture-1e-9": ({"aperture": 1e-9}, None, None, run, ()),
        "aperture-1": ({"aperture": 1.0}, None, None, run, ()),
        "aperture-1e-110": ({"aperture": 1e-110}, None, None, refused, ("aperture",)),
        "aperture-1e110": ({"aperture": 1e110}, None, None, refused, ("aperture",)),
        "aperture-subnormal": (
            {"aperture": 5e-324},
            None,
            None,
            refused,
            ("aperture",),
        ),
        "aperture-0": ({"aperture": 0.0}, None, None, refused, ("aperture",)),
        "hydraulic-aperture-1e-110": (
            {"aperture": A0},
            {"aperture": 1e-110},
            None,
            refused,
            ("fractures[0].hydraulic.aperture",),
        ),
        "dilation-angle-89.999999": (
            {"aperture": A0, "dilation_angle": 89.999999},
            None,
            None,
            run,
            (),
        ),
        "dilation-angle-90": (
            {"aperture": A0, "dilation_angle": 90.0},
            None,
            None,
            refused,
            ("dilation_angle",),
        ),
        "dilation-slip-1e-300": (
            {"aperture": A0, "dilation_angle": 10.0, "dilation_slip": 1e-300},
            None,
            None,
            run,
            (),
        ),
        "dilation-slip-1e300": (
            {"aperture": A0, "dilation_angle": 10.0, "dilation_slip": 1e300},
            None,
            None,
            run,
            (),
        ),
        "max-closure-aperture": (
            {"aperture": A0, "max_closure": A0, **K},
            None,
            None,
            run,
            (),
        ),
        "max-closure-subnormal": (
            {"aperture": A0, "max_closure": 5e-324, **K},
            None,
            None,
            run,
            (),
        ),
        "max-closure-above": (
            {"aperture": A0, "max_closure": 2 * A0, **K},
            None,
            None,
            refused,
            ("max_closure",),
        ),
        "stiffness-1e3": (
            {"aperture": A0, "max_closure": A0, "normal_stiffness": 1e3},
            None,
            None,
            run,
            (),
        ),
        "stiffness-1e16": (
            {"aperture": A0, "max_closure": A0, "normal_stiffness": 1e16},
            None,
            None,
            run,
            (),
        ),
        "stiffness-subnormal": (
            {"aperture": A0, "max_closure": A0, "normal_stiffness": 5e-324},
            None,
            None,
            refused,
            ("normal_stiffness",),
        ),
        "stiffness-1e300": (
            {"aperture": A0, "max_closure": A0, "normal_stiffness": 1e300},
            None,
            None,
            refused,
            ("normal_stiffness",),
        ),
        "matrix-1e-6": ({"aperture": A0, "matrix": 1e-6}, None, None, run, ()),
        "matrix-1e300": (
            {"aperture": A0, "matrix": 1e300},
            None,
            None,
            refused,
            ("matrix",),
        ),
        "block-one-cell": (
            {"aperture": A0, "block": [0.0, 0.0, CELL, CELL]},
            None,
            None,
            run,
            (),
        ),
        "block-1e-200": (
            {"aperture": A0, "block": [0.0, 0.0, 1e-200, 1e-200]},
            None,
            None,
            refused,
            ("block",),
        ),
        "block-thin": (
            {"aperture": A0, "block": [0.0, 0.0, 1.0, 1e-9]},
            None,
            None,
            refused,
            ("block",),
        ),
        "extent-1e-3": (None, None, {"extent": 1e-3}, run, ()),
        "extent-1e7": (None, None, {"extent": 1e7}, run, ()),
        "extent-1e300": (None, None, {"extent": 1e300}, refused, ("events.extent",)),
        "extent-subnormal": (
            None,
            None,
            {"extent": 5e-324},
            refused,
            ("events.extent",),
        ),
    }
    out = []
    for name, (perm, hydraulic, events, expect, names) in cases.items():
        doc = _post_case(perm, events, hydraulic)
        out.append(_post_input(name, doc, expect, names))
    # the closure law from no in-situ stress: a0 - V_m at full closure
    for stiffness in (1e3, 1e10, 1e16):
        doc = _post_case(
            {"aperture": A0, "max_closure": A0, "normal_stiffness": stiffness},
            initial=False,
        )
        out.append(
            _post_input(f"max-closure-aperture-no-initial-{stiffness:g}", doc, run, ())
        )
    return out


def _post_input(name: str, doc: dict, expect, names) -> Input:
    return Input(
        id=f"post-keys/{name}",
        family="post-keys",
        files={"case.toml": toml(doc)},
        argv=("run", "case.toml", "-o", OUT),
        expect=expect,
        names=("case.toml", *names) if expect == frozenset({2}) else (),
    )


# --------------------------------------------------------------------------- #
# dfn --summary: a sweep's summary.csv
# --------------------------------------------------------------------------- #


def dfn_summary_inputs() -> list[Input]:
    """Counts of slipping fractures that hang a histogram or overflow, cells
    over csv's field limit, bytes that are not CSV."""
    head = "case,status,slipping_fractures,fractures\n"
    ok, refused = frozenset({0}), frozenset({2})

    def rows(*pairs) -> str:
        return head + "".join(f"{i:03d},ok,{s},{t}\n" for i, (s, t) in enumerate(pairs))

    cases = {
        "valid": (rows((1, 4), (2, 4), (0, 4)), ok),
        "count-1e6": (rows((0, 1_000_000), (1_000_000, 1_000_000)), ok),
        "count-1e11": (rows((0, 10**11), (10**11, 10**11)), refused),
        "count-beyond-int64": (rows((0, 2**70), (2**70, 2**70)), refused),
        "count-4300-digits": (rows((1, int("9" * 4300))), refused),
        "count-negative": (rows((-1, 4)), refused),
        "slipping-above-total": (rows((5, 4)), refused),
        "count-float": (rows(("1e6", "1e6")), refused),
        "cell-200kB": (head + "000,ok," + "1" * 200_000 + ",4\n", refused),
        "nul-byte": (head + "000,ok,1\x00,4\n", refused),
        "unclosed-quote": (head + '000,ok,"1,4\n', refused),
        "wide-spread": (rows(*[(k * 997, 200_000) for k in range(200)]), ok),
        "many-rows": (rows(*[(k % 5, 4) for k in range(20_000)]), ok),
    }
    case = toml(network_case(generate=GENERATE))
    return [
        Input(
            id=f"dfn-summary/{name}",
            family="dfn-summary",
            files={"case.toml": case, "summary.csv": text},
            argv=("dfn", "case.toml", "--plot", "net.png", "--summary", "summary.csv"),
            expect=expect,
            names=("summary.csv",) if expect == refused else (),
            out=None,
            timeout=60.0,
        )
        for name, (text, expect) in cases.items()
    ]


# --------------------------------------------------------------------------- #
# Cases from standard input
# --------------------------------------------------------------------------- #


def stdin_inputs() -> list[Input]:
    """``run -`` and ``check -``: a case on standard input, read with the cap
    of a case file; its CSV files relative to the working directory."""
    case = toml(DEPLETION).encode()
    csv_case = copy.deepcopy(DEPLETION)
    csv_case["boundary"]["left"] = {"file": "left.csv"}
    left = "x,y,ux,uy\n0.0,0.0,0.0,0.0\n0.0,1.0,0.0,0.0\n"
    cases = {
        "run": (case, ("run", "-q", "-", "-o", OUT), {}, frozenset({0})),
        "check": (case, ("check", "-"), {}, frozenset({0})),
        "csv-relative-to-cwd": (
            toml(csv_case).encode(),
            ("run", "-q", "-", "-o", OUT),
            {"left.csv": left},
            frozenset({0}),
        ),
        "empty": (b"", ("run", "-q", "-", "-o", OUT), {}, frozenset({2})),
        "not-toml": (b"x = = 1\n", ("run", "-q", "-", "-o", OUT), {}, frozenset({2})),
        "9MB": (
            case + b"# " + b"x" * (9 * 2**20) + b"\n",
            ("run", "-q", "-", "-o", OUT),
            {},
            frozenset({2}),
        ),
        "not-utf8": (b"\xff\xfe\x00x", ("check", "-"), {}, frozenset({2})),
    }
    return [
        Input(
            id=f"stdin/{name}",
            family="stdin",
            files=files,
            argv=argv,
            stdin=data,
            expect=expect,
            names=("-",) if expect == frozenset({2}) else (),
        )
        for name, (data, argv, files, expect) in cases.items()
    ]
