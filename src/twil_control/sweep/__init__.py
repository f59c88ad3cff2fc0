"""Sweeps: one launch file run many times with varied args, in parallel on Dask.

``load_sweep`` reads a sweep file, ``run_sweep`` runs it; ``python -m twil_control.sweep`` is
the command line.
"""

from .execute import SweepOutcome, run_sweep
from .spec import Sweep, SweepError, load_sweep

__all__ = ["Sweep", "SweepError", "SweepOutcome", "load_sweep", "run_sweep"]
