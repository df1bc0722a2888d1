"""``python -m xfemslip``: the command-line interface (see :mod:`xfemslip.cli`)."""

from xfemslip.cli import main

main()
