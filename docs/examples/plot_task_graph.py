"""
The task graph on a local cluster
=================================

Every stage is also a lazy ``dask.delayed`` task (:mod:`hht3d.graph`): EMD is one task, and the
Riesz transform of all IMFs is split into shift-group tasks that run in parallel.  Here the
graph of one HHT, computed on a local ``dask.distributed`` cluster of two worker processes.  In
a script, start worker processes under ``if __name__ == "__main__":`` (each worker imports the
main script again).
"""

import tempfile
from pathlib import Path

import hht3d
from hht3d import graph

out = Path(tempfile.mkdtemp())
surface = graph.load(hht3d.data_path("spot.ply"))
lazy = graph.hht(surface, graph.signal(surface, "mean_curvature"), max_imfs=2, riesz_tasks=2)
saved = graph.save(lazy, out / "spot_hht.npz")
print(len(lazy.__dask_graph__()), "tasks")

# %%
# ``scheduler="distributed"`` starts a ``LocalCluster`` (closed afterwards); ``address=`` would
# use a running one.
result, path = graph.compute(lazy, saved, scheduler="distributed", workers=2, progress=False)
print(path.name)
result
