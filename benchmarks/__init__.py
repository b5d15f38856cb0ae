"""Benchmarks of hht3d (not tests): each ``bench_*.py`` runs from the repository root as
``python -m benchmarks.bench_NAME`` and writes its JSON and Markdown to ``benchmarks/results/``.

Shared pieces: :mod:`benchmarks.common` (paths, memory, timing, machine facts, worker processes,
result files and Markdown), :mod:`benchmarks.meshes` (generated meshes), :mod:`benchmarks.servers`
(an S3 server and a Dask cluster on this machine).  See ``benchmarks/README.md``.
"""
