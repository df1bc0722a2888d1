"""Studies made of many runs: sweeps over parameters and random networks,
critical depletion, sampling.

Modules:

- ``sweep``: sweep files: a base case plus the parameters to vary;
- ``vary``: the ``[vary]`` table: key paths, value lists and ranges;
- ``sampling``: random samples of uncertain inputs;
- ``uncertainty``: the ``[uncertainty]`` table of a sweep file (``inputs``:
  its distributions and correlations);
- ``slip_screen``: the closed-form critical change of many samples along a
  case's stress path;
- ``reactivation``: the samples evaluated (screen or deplete) and counted
  into probabilities of slip (``uncertainty_output``: its files);
- ``run``: running a sweep (processes or Dask), reruns, the summary;
- ``dfn_summary``: the aggregate of a sweep over network realizations;
- ``depletion``: the pore-pressure drop at which each fracture first slips.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.studies.sweep import ...``)."""

__all__ = [
    "depletion",
    "dfn_summary",
    "inputs",
    "reactivation",
    "run",
    "sampling",
    "slip_screen",
    "sweep",
    "uncertainty",
    "uncertainty_output",
    "vary",
]
