"""Studies made of many runs: sweeps over parameters and random networks,
critical depletion, sampling.

Modules:

- ``sweep``: sweep files: a base case plus the parameters to vary;
- ``vary``: the ``[vary]`` table: key paths, value lists and ranges;
- ``sampling``: random samples of uncertain inputs;
- ``run``: running a sweep (processes or Dask), reruns, the summary;
- ``dfn_summary``: the aggregate of a sweep over network realizations;
- ``depletion``: the pore-pressure drop at which each fracture first slips.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.studies.sweep import ...``)."""

__all__ = ["depletion", "dfn_summary", "run", "sampling", "sweep", "vary"]
