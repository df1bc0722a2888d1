"""Study families of the bad-input suite: sweeps (sizes counted before
expansion, overflowing ranges, long case ids), random networks whose derived
sizes overflow, depletion."""

from __future__ import annotations

import copy
import math

from tests.support.bad_inputs.base import (
    BIG_INT_TEXT,
    DEPLETION,
    GENERATE,
    OUT,
    Input,
    network_case,
    small,
    toml,
)

# --------------------------------------------------------------------------- #
# Sweeps
# --------------------------------------------------------------------------- #


# 26 keys, each with its base value: the case folders' names hold every key
MANY_KEYS = "\n".join(
    f'"{key}" = [{value}]'
    for key, value in [
        *[(f"fractures[0].{k}", v) for k, v in (("friction", 0.3), ("cohesion", 0.0))],
        *[(f"fractures[0].{k}", "1e12") for k in ("kn", "kt")],
        ("fractures[0].tip", '"ramp"'),
        *[(f"solver.{k}", v) for k, v in (("tolerance", 1e-8), ("max_iterations", 30))],
        *[
            (f"solver.{k}", v)
            for k, v in (("contact_patch", 1.5), ("max_step_cuts", 5))
        ],
        ("solver.tangent", '"consistent"'),
        ("solver.linear_solver", '"superlu"'),
        ("solver.kernels", '"numpy"'),
        ("material.E", "1e9"),
        ("material.nu", 0.25),
        ("material.model", '"plane_strain"'),
        ("loading.steps", 1),
        *[(f"loading.stress.{k}", v) for k, v in (("xx", -1e6), ("yy", -2e6))],
        ("loading.stress.xy", 0.0),
        ("domain.size[0]", 1.0),
        ("domain.size[1]", 1.0),
        ("domain.origin[0]", 0.0),
        ("domain.origin[1]", 0.0),
        ("mesh.elements[0]", 4),
        ("mesh.elements[1]", 4),
        ("boundary.top", '"traction"'),
    ]
)


def sweep_inputs() -> list[Input]:
    base = toml(small(loading={"stress": {"xx": -1e6, "yy": -2e6}, "steps": 1}))
    vary_1e12 = (
        "\n".join(
            f'"fractures[0].{k}" = {{ start = 0.0, stop = 99.0, step = 1.0 }}'
            for k in ("friction", "cohesion", "kn", "kt")
        )
        + '\n"material.E" = { start = 1.0, stop = 100.0, num = 100 }\n'
    )
    vary_1e12 += '"material.nu" = { start = 0.0, stop = 0.4, num = 100 }\n'
    sweeps = {
        "valid": ('"fractures[0].friction" = [0.2, 0.4]', {0, 1}, ()),
        "product-1e12": (vary_1e12, {2}, ("vary",)),
        "step-1e-300": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = 1e-300 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-subnormal": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = 5e-324 }',
            {2},
            ("fractures[0].friction",),
        ),
        "span-overflow": (
            '"fractures[0].friction" = { start = -1e308, stop = 1e308, step = 1e300 }',
            {2},
            ("fractures[0].friction",),
        ),
        "span-overflow-num": (
            '"fractures[0].friction" = { start = -1e308, stop = 1e308, num = 3 }',
            {2},
            ("fractures[0].friction",),
        ),
        "int-span-beyond-float": (
            f'"loading.steps" = {{ start = 1, stop = {BIG_INT_TEXT}, step = 1 }}',
            {2},
            ("loading.steps",),
        ),
        "num-1e9": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, num = 1000000000 }',
            {2},
            ("fractures[0].friction",),
        ),
        "num-0": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, num = 0 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-0": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = 0.0 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-wrong-way": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = -0.1 }',
            {2},
            ("fractures[0].friction",),
        ),
        "step-nan": (
            '"fractures[0].friction" = { start = 0.0, stop = 1.0, step = nan }',
            {2},
            ("fractures[0].friction",),
        ),
        "empty-list": ('"fractures[0].friction" = []', {2}, ()),
        "bad-key-path": ('"fractures[0]..friction" = [0.1]', {2}, ()),
        "missing-index": ('"fractures[7].friction" = [0.1]', {2}, ("fractures[7]",)),
        # the valid member runs, the other is refused alone (exit 1)
        "invalid-member": (
            '"fractures[0].friction" = [0.2, -1.0]',
            {1},
            ("fractures[0].friction: must be >= 0",),
        ),
        "overlap": (
            '"fractures[0]" = [{ points = [[0.2, 0.3], [0.8, 0.7]], friction = 0.3 }]'
            '\n"fractures[0].friction" = [0.2]',
            {2},
            ("overlaps",),
        ),
        "zip-unequal": (
            '"fractures[0].friction" = [0.2, 0.4]\n"material.E" = [1e9]',
            {2},
            ("zip",),
        ),
        "10k-single-keys": (
            "\n".join(f'"material.k{i}" = [1]' for i in range(10_000)),
            {2},
            (),
        ),
        "many-keys-long-case-id": (MANY_KEYS, {0, 1}, ()),
    }
    out = []
    for name, (vary, expect, names) in sweeps.items():
        combine = 'combine = "zip"\n' if name == "zip-unequal" else ""
        text = f'name = "sw"\nbase = "base.toml"\n{combine}\n[vary]\n{vary}\n'
        out.append(
            Input(
                id=f"sweep/{name}",
                family="sweep",
                files={"sweep.toml": text, "base.toml": base},
                argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
                expect=frozenset(expect),
                names=("sweep.toml", *names) if expect == {2} else names,
                timeout=60.0,
            )
        )
    heads = {
        "name-slash": ('name = "a/b"\nbase = "base.toml"', ("name",)),
        "name-300": (f'name = "{"n" * 300}"\nbase = "base.toml"', ("name",)),
        "no-base": ('name = "sw"', ("base",)),
        "base-missing": ('name = "sw"\nbase = "nope.toml"', ("base",)),
        "base-number": ('name = "sw"\nbase = 5', ("base",)),
        "combine-bad": ('base = "base.toml"\ncombine = "cross"', ("combine",)),
        "dir-nul": (
            'base = "base.toml"\n[output]\ndirectory = "a\\u0000b"',
            ("output.directory",),
        ),
        "dir-long": (
            f'base = "base.toml"\n[output]\ndirectory = "{"d" * 300}"',
            ("output.directory",),
        ),
    }
    for name, (head, names) in heads.items():
        vary = '[vary]\n"fractures[0].friction" = [0.2]\n'
        if "[output]" in head:
            text = head.replace("[output]", vary + "\n[output]")
        else:
            text = f"{head}\n{vary}"
        out.append(
            Input(
                id=f"sweep/{name}",
                family="sweep",
                files={"sweep.toml": text, "base.toml": base},
                argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml")
                if "dir-" not in name
                else ("sweep", "-j", "1", "sweep.toml"),
                names=("sweep.toml", *names),
            )
        )
    big = small()
    big["fractures"] = [
        dict(big["fractures"][0], friction=0.3 + 1e-6 * i) for i in range(6000)
    ]
    out.append(
        Input(
            id="sweep/volume-1MB-base-x-10000",
            family="sweep",
            files={
                "sweep.toml": 'base = "base.toml"\n[vary]\n"material.nu" = '
                "{ start = 0.0, stop = 0.4, num = 10000 }\n",
                "base.toml": toml(big),
            },
            argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
            names=("sweep.toml", "vary"),
            timeout=60.0,
        )
    )
    return out


# --------------------------------------------------------------------------- #
# Random networks, depletion
# --------------------------------------------------------------------------- #


def generate_inputs() -> list[Input]:
    """[network.generate] values whose derived sizes overflow or degenerate."""
    power = {"distribution": "power_law", "exponent": 2.5, "min": 0.2, "max": 0.4}
    lognormal = {"distribution": "lognormal", "median": 0.3, "sigma": 0.5}
    changes = {
        "p21-1e308": ({"p21": 1e308}, ("count",), "p21"),
        "p20-1e308": ({"p20": 1e308}, ("count",), "p20"),
        "p21-tiny": ({"p21": 1e-300}, ("count",), None),
        "count-5001": ({"count": 5001}, (), "count"),
        "count-2**64": ({"count": 2**64}, (), "count"),
        "seed-2**64": ({"seed": 2**64}, (), None),
        "seed-negative": ({"seed": -1}, (), "seed"),
        "powerlaw-min-1e-300": (
            {"length": dict(power, min=1e-300)},
            (),
            "length",
        ),
        "powerlaw-max-1e308": ({"length": dict(power, max=1e308)}, (), None),
        "powerlaw-exp-10-min-1e-40": (
            {"length": dict(power, exponent=10.0, min=1e-40)},
            (),
            "length",
        ),
        "powerlaw-exp--10-max-1e300": (
            {"length": dict(power, exponent=-10.0, max=1e300)},
            (),
            "length",
        ),
        "powerlaw-min=max": ({"length": dict(power, min=0.3, max=0.3)}, (), "max"),
        "lognormal-median-1e308": (
            {"length": dict(lognormal, median=1e308, sigma=10.0)},
            (),
            "length",
        ),
        "lognormal-median-1e-300": (
            {"length": dict(lognormal, median=1e-300)},
            (),
            None,
        ),
        "lognormal-empty-window": (
            {"length": dict(lognormal, min=100.0, max=101.0)},
            (),
            "length",
        ),
        "constant-1e308": (
            {"length": {"distribution": "constant", "value": 1e308}},
            (),
            None,
        ),
        "region-huge": ({"region": [[-1e308, -1e308], [1e308, 1e308]]}, (), "region"),
        "region-point": ({"region": [[0.5, 0.5], [0.5, 0.5]]}, (), "region"),
        "region-away": (
            {"region": [[5.0, 5.0], [6.0, 6.0]], "outside": "reject"},
            (),
            None,
        ),
        "kappa-1e6": (
            {"orientation": {"distribution": "von_mises", "mean": 0.0, "kappa": 1e6}},
            (),
            None,
        ),
        "std-360": (
            {"orientation": {"distribution": "normal", "mean": 1e308, "std": 360.0}},
            (),
            None,
        ),
        "avoid-spacing-1e308": (
            {"intersections": "avoid", "min_spacing": 1e308, "count": 50},
            (),
            "generate",
        ),
        "clip-min-length-1e308": ({"min_length": 1e308}, (), "generate"),
        "sets-weights-extreme": (
            {
                "sets": [
                    {
                        "weight": 1e-300,
                        "orientation": {"distribution": "uniform"},
                        "length": power,
                    },
                    {
                        "weight": 1e308,
                        "orientation": {"distribution": "uniform"},
                        "length": power,
                    },
                ]
            },
            ("orientation", "length"),
            None,
        ),
    }
    out = []
    for name, (change, drop, must) in changes.items():
        generate = copy.deepcopy(GENERATE)
        for key in drop:
            generate.pop(key, None)
        generate.update(change)
        out.append(
            Input(
                id=f"generate/{name}",
                family="network-generate",
                files={"case.toml": toml(network_case(generate=generate))},
                argv=("check", "case.toml"),
                expect=frozenset({2}) if must else frozenset({0, 2}),
                names=("case.toml", "network.generate", *([must] if must else [])),
                out=None,
            )
        )
    return out


def depletion_inputs() -> list[Input]:
    out = []
    cases = {
        "change-0": ({"change": 0.0}, (), {2}, ("pore_pressure.change",)),
        "change--0.0": ({"change": -0.0}, (), {2}, ("pore_pressure.change",)),
        "change-nan": ({"change": math.nan}, (), {2}, ("pore_pressure.change",)),
        "change-1e308": ({"change": -1e308}, (), {0, 1, 2}, ()),
        "valid": ({}, (), {0, 1}, ()),
        "tolerance-0": ({}, ("--tolerance", "0"), {2}, ("--tolerance",)),
        "tolerance-negative": ({}, ("--tolerance", "-1"), {2}, ("--tolerance",)),
        "tolerance-nan": ({}, ("--tolerance", "nan"), {2}, ("--tolerance",)),
        "tolerance-text": ({}, ("--tolerance", "abc"), {2}, ("--tolerance",)),
        "tolerance-inf": ({}, ("--tolerance", "inf"), {0, 1, 2}, ()),
        "tolerance-huge": ({}, ("--tolerance", "1e300"), {0, 1}, ()),
    }
    for name, (change, options, expect, names) in cases.items():
        doc = copy.deepcopy(DEPLETION)
        doc["pore_pressure"].update(change)
        out.append(
            Input(
                id=f"deplete/{name}",
                family="deplete",
                files={"case.toml": toml(doc)},
                argv=("deplete", "-q", "case.toml", "-o", OUT, *options),
                expect=frozenset(expect),
                names=names,
            )
        )
    no_pp = copy.deepcopy(DEPLETION)
    del no_pp["pore_pressure"]
    no_fr = copy.deepcopy(DEPLETION)
    del no_fr["fractures"]
    for name, doc in (("no-pore-pressure", no_pp), ("no-fracture", no_fr)):
        out.append(
            Input(
                id=f"deplete/{name}",
                family="deplete",
                files={"case.toml": toml(doc)},
                argv=("deplete", "-q", "case.toml", "-o", OUT),
                names=("case.toml",),
            )
        )
    return out


# --------------------------------------------------------------------------- #
# Uncertainty studies
# --------------------------------------------------------------------------- #


def _uncertainty_text(head: str, inputs: str, extra: str = "") -> str:
    return (
        f'name = "un"\nbase = "base.toml"\n\n[uncertainty]\n{head}\n'
        f"\n[uncertainty.inputs]\n{inputs}\n{extra}"
    )


FRICTION = (
    '"fractures[0].friction" = { distribution = "uniform", low = 0.3, high = 0.7 }'
)
SCREEN = 'samples = 50\nseed = 1\nevaluate = "screen"\nlevels = [0.0, -5.0e5, -1.0e6]'


def uncertainty_inputs() -> list[Input]:
    """[uncertainty] sweep files on the small depletion case: every key with
    values out of range, of the wrong type, sizes that must be bounded before
    anything is drawn, and a valid one that runs."""
    base = toml(DEPLETION)
    dist = {
        "unknown": '{ distribution = "weibull", low = 0.1, high = 0.5 }',
        "uniform-reversed": '{ distribution = "uniform", low = 0.7, high = 0.3 }',
        "uniform-nan": '{ distribution = "uniform", low = nan, high = 0.3 }',
        "normal-std-negative": '{ distribution = "normal", mean = 0.5, std = -0.1 }',
        "normal-trunc-empty": (
            '{ distribution = "normal", mean = 0.5, std = 0.1, low = 0.9, high = 0.8 }'
        ),
        "lognormal-median-0": (
            '{ distribution = "lognormal", median = 0.0, sigma = 0.2 }'
        ),
        "lognormal-sigma-inf": (
            '{ distribution = "lognormal", median = 0.5, sigma = inf }'
        ),
        "triangular-mode-outside": (
            '{ distribution = "triangular", low = 0.2, mode = 0.9, high = 0.6 }'
        ),
        "choice-empty": '{ distribution = "choice", values = [] }',
        "choice-weights-negative": (
            '{ distribution = "choice", values = [0.3, 0.5], weights = [1.0, -1.0] }'
        ),
        "choice-weights-count": (
            '{ distribution = "choice", values = [0.3, 0.5], weights = [1.0] }'
        ),
        "missing-parameter": '{ distribution = "normal", mean = 0.5 }',
        "not-a-table": "0.5",
        "string": '"uniform"',
    }
    cases = {
        f"dist-{name}": (
            SCREEN,
            f'"fractures[0].friction" = {value}',
            "",
            ("fractures[0].friction",),
        )
        for name, value in dist.items()
    }
    heads = {
        "samples-0": ("samples = 0", "samples"),
        "samples-negative": ("samples = -5", "samples"),
        "samples-1e12": ("samples = 1000000000000", "samples"),
        "samples-float": ("samples = 10.5", "samples"),
        "samples-big-int": (f"samples = {BIG_INT_TEXT}", "samples"),
        "method-bad": ('method = "sobol"', "method"),
        "evaluate-bad": ('evaluate = "exact"', "evaluate"),
        "confidence-1": ("confidence = 1.0", "confidence"),
        "confidence-nan": ("confidence = nan", "confidence"),
        "seed-negative": ("seed = -1", "seed"),
        "levels-wrong-sign": ("levels = [1.0e6]", "levels"),
        "levels-beyond-change": ("levels = [-5.0e6]", "levels"),
        "levels-empty": ("levels = []", "levels"),
        "levels-num-1e9": (
            "levels = { start = 0.0, stop = -1.0e6, num = 1000000000 }",
            "levels",
        ),
        "levels-step-0": (
            "levels = { start = 0.0, stop = -1.0e6, step = 0.0 }",
            "levels",
        ),
        "unknown-key": ("sampels = 10", "sampels"),
    }
    for name, (line, key) in heads.items():
        key_name = key.split(".")[-1]
        head = "\n".join(
            ln for ln in SCREEN.splitlines() if not ln.startswith(key_name + " ")
        )
        cases[f"head-{name}"] = (head + "\n" + line, FRICTION, "", (key,))
    corr = {
        "rho-2": 'keys = ["fractures[0].friction", "material.E"]\nrho = 2.0',
        "same-key": (
            'keys = ["fractures[0].friction", "fractures[0].friction"]\nrho = 0.5'
        ),
        "not-an-input": 'keys = ["fractures[0].friction", "material.nu"]\nrho = 0.5',
        "one-key": 'keys = ["fractures[0].friction"]\nrho = 0.5',
    }
    two = FRICTION + (
        '\n"material.E" = { distribution = "uniform", low = 0.9e9, high = 1.1e9 }'
    )
    for name, body in corr.items():
        cases[f"corr-{name}"] = (
            SCREEN.replace('evaluate = "screen"', 'evaluate = "xfem"'),
            two,
            f"\n[[uncertainty.correlation]]\n{body}\n",
            ("correlation",),
        )
    cases["input-unknown-key"] = (
        SCREEN,
        '"material.Young" = { distribution = "uniform", low = 1.0, high = 2.0 }',
        "",
        ("material.Young",),
    )
    cases["input-axis-key"] = (
        SCREEN,
        '"pore_pressure.change" = '
        '{ distribution = "uniform", low = -2e6, high = -1e6 }',
        "",
        ("pore_pressure.change",),
    )
    cases["no-inputs"] = (SCREEN, "", "", ("inputs",))
    out = []
    for name, (head, inputs, extra, names) in cases.items():
        out.append(
            Input(
                id=f"uncertainty/{name}",
                family="uncertainty",
                files={
                    "sweep.toml": _uncertainty_text(head, inputs, extra),
                    "base.toml": base,
                },
                argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
                names=("sweep.toml", *names),
            )
        )
    both = _uncertainty_text(SCREEN, FRICTION) + '\n[vary]\n"material.E" = [1e9]\n'
    out.append(
        Input(
            id="uncertainty/vary-and-uncertainty",
            family="uncertainty",
            files={"sweep.toml": both, "base.toml": base},
            argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
            names=("sweep.toml",),
        )
    )
    out.append(
        Input(
            id="uncertainty/valid-screen",
            family="uncertainty",
            files={
                "sweep.toml": _uncertainty_text(SCREEN, FRICTION),
                "base.toml": base,
            },
            argv=("sweep", "-j", "1", "-o", OUT, "sweep.toml"),
            expect=frozenset({0}),
        )
    )
    return out
