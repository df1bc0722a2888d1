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
sizes, geometry of many vertices), ``results.py`` (corrupted, truncated,
partial and foreign result files through every command that reads one) and
``edges.py`` (distributions of uncertainty studies at their edges, every
post-processing key at its bounds, ``dfn --summary`` tables, cases on
standard input); ``base.py`` holds what they share.

This module assembles the two tiers.  ``every_input()`` is the whole
generated suite; the default test run takes a deterministic sample of it
(``default_inputs``: about one input in SAMPLE_EVERY of each family, at
least MIN_PER_FAMILY, chosen by a checksum of the input's id, so the same
inputs every time), the slow tier (``--run-slow``) all the others and the
larger sweep of mutated keys (``slow_inputs``).
"""

from __future__ import annotations

import functools
import random
import zlib

from tests.support.bad_inputs.base import Input
from tests.support.bad_inputs.commands import (
    cli_inputs,
    environment_inputs,
    shape_inputs,
    size_inputs,
)
from tests.support.bad_inputs.edges import (
    dfn_summary_inputs,
    post_key_inputs,
    stdin_inputs,
    uncertainty_edge_inputs,
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
from tests.support.bad_inputs.results import result_inputs
from tests.support.bad_inputs.studies import (
    depletion_inputs,
    generate_inputs,
    sweep_inputs,
    uncertainty_inputs,
)

SEED = 20240613


SAMPLE_EVERY = 12
MIN_PER_FAMILY = 3


def every_input() -> list[Input]:
    """The whole generated suite (about 1,800 inputs)."""
    return list(_every_input())


@functools.cache
def _every_input() -> tuple[Input, ...]:
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
        *result_inputs(),
        *uncertainty_edge_inputs(),
        *post_key_inputs(),
        *dfn_summary_inputs(),
        *stdin_inputs(),
    ]
    ids = [i.id for i in inputs]
    assert len(ids) == len(set(ids)), "input ids must be unique"
    return tuple(inputs)


def _sampled(inputs: list[Input]) -> set[str]:
    """Ids of the default tier's sample: per family, the inputs whose id has
    the smallest CRC-32, one in SAMPLE_EVERY and at least MIN_PER_FAMILY."""
    families: dict[str, list[Input]] = {}
    for item in inputs:
        families.setdefault(item.family, []).append(item)
    chosen = set()
    for items in families.values():
        count = max(MIN_PER_FAMILY, -(-len(items) // SAMPLE_EVERY))
        ranked = sorted(items, key=lambda i: zlib.crc32(i.id.encode()))
        chosen.update(i.id for i in ranked[:count])
    return chosen


def default_inputs() -> list[Input]:
    """The sample of every_input() the default test run takes (module doc)."""
    inputs = every_input()
    chosen = _sampled(inputs)
    return [i for i in inputs if i.id in chosen]


def slow_inputs() -> list[Input]:
    """The slow tier: every input the default sample leaves out, then the
    larger sweep of mutated keys (every key of the shipped cases with three
    mutations, many more runs of the small case)."""
    inputs = every_input()
    chosen = _sampled(inputs)
    rest = [i for i in inputs if i.id not in chosen]
    rng = random.Random(SEED + 1)
    more = [*shipped_key_inputs(rng, per_key=3), *small_key_inputs(rng, 600)]
    return rest + [Input(**{**i.__dict__, "id": f"slow/{i.id}"}) for i in more]
