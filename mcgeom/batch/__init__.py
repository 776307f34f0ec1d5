"""Batch odometry over many sequences on Dask distributed (``mcgeom batch``).

``manifest``: the CSV of sequences; ``task``: one sequence, run and
summarised (what a worker runs); ``runner``: the Dask client, the tasks, the
summary files. Needs the ``batch`` extra (``pip install 'mcgeom[batch]'``);
the rest of mcgeom never imports Dask.
"""

from .manifest import ManifestEntry, read_manifest
from .runner import connect, run, write_summary
from .task import SUMMARY_COLUMNS, run_sequence

__all__ = ["ManifestEntry", "read_manifest", "run", "connect", "write_summary",
           "run_sequence", "SUMMARY_COLUMNS"]
