"""Generated bad and edge-case inputs of the whole CLI, for test_bad_inputs.py.

Each ``Input`` is a folder of files (case, sweep, CSV files, special files), a
command line, an environment, and what may come out: the allowed exit codes
(0 run, 1 clean failure, 2 refusal) and, where the input breaks one key, the
key the refusal must name.  The generators are deterministic (``random.Random``
with a fixed seed), so a failing input is found again by its id.

The families (``Input.family``) are generated in ``keys.py`` (the
keys of the shipped cases mutated one at a time through ``check``, those of a
small case through ``check`` and ``run``, misspelt keys), ``files.py``
(TOML nesting depth, special and oversized files in every place a file is
read, bytes that are not clean UTF-8 TOML, boundary and network CSV files),
``studies.py`` (sweeps, uncertainty studies, random networks, depletion) and
``commands.py`` (command-line options, environment variables,
sizes, geometry of many vertices); ``base.py`` holds what they
share.  This module assembles the two suites.
"""

from __future__ import annotations

import random

from tests.support.bad_inputs.base import Input
from tests.support.bad_inputs.commands import (
    cli_inputs,
    environment_inputs,
    shape_inputs,
    size_inputs,
)
from tests.support.bad_inputs.files import (
    boundary_csv_inputs,
    byte_inputs,
    nesting_inputs,
    network_csv_inputs,
    special_file_inputs,
)
from tests.support.bad_inputs.keys import (
    shipped_key_inputs,
    small_key_inputs,
    small_systematic_inputs,
    unknown_key_inputs,
)
from tests.support.bad_inputs.studies import (
    depletion_inputs,
    generate_inputs,
    sweep_inputs,
    uncertainty_inputs,
)

SEED = 20240613


def default_inputs() -> list[Input]:
    """The suite of the default test run (a few hundred inputs)."""
    rng = random.Random(SEED)
    inputs = [
        *shipped_key_inputs(rng, per_key=1),
        *small_key_inputs(rng, 80),
        *small_systematic_inputs(),
        *unknown_key_inputs(),
        *nesting_inputs(),
        *special_file_inputs(),
        *byte_inputs(rng),
        *boundary_csv_inputs(),
        *network_csv_inputs(),
        *sweep_inputs(),
        *uncertainty_inputs(),
        *generate_inputs(),
        *depletion_inputs(),
        *cli_inputs(),
        *environment_inputs(),
        *size_inputs(),
        *shape_inputs(),
    ]
    ids = [i.id for i in inputs]
    assert len(ids) == len(set(ids)), "input ids must be unique"
    return inputs


def slow_inputs() -> list[Input]:
    """The larger sweep behind --run-slow: every key of the shipped cases with
    three mutations, and many more runs of the small case."""
    rng = random.Random(SEED + 1)
    inputs = [*shipped_key_inputs(rng, per_key=3), *small_key_inputs(rng, 600)]
    return [Input(**{**i.__dict__, "id": f"slow/{i.id}"}) for i in inputs]
