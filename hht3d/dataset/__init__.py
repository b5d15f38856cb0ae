"""Datasets of many files: one guarded subgraph per file, outputs written safely, summaries.

* :mod:`~hht3d.dataset.run` — :func:`run_dataset` and :func:`dataset_graph`, and the loop
  shared with the pipeline runner (:func:`~hht3d.dataset.run.items_graph`);
* :mod:`~hht3d.dataset.guard` — a failing task becomes a record of its step and reason;
* :mod:`~hht3d.dataset.summary` — one row per file, ``summary.json`` and ``summary.csv``.
"""

from .run import RESULT_SUFFIXES, dataset_graph, output_paths, run_dataset
from .summary import ItemSummary, write_summary

__all__ = ["RESULT_SUFFIXES", "ItemSummary", "dataset_graph", "output_paths", "run_dataset", "write_summary"]
