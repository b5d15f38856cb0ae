"""
A point cloud
=============

A point cloud has no faces: its Laplacian and vertex areas come from a local triangulation of
each point's neighbourhood (``robust_laplacian``), and everything else is the same.  Here the
cow's vertices alone, with the distance to the centroid as the signal.
"""

import hht3d
from hht3d.geometry import centroid_distance
from hht3d.viz import hht_figure

mesh = hht3d.load(hht3d.data_path("spot.ply"))
cloud = hht3d.Surface(mesh.vertices, None, name="spot points")
result = hht3d.hht(cloud, centroid_distance(cloud), max_imfs=2)
print(cloud)
result

# %%
# The points are drawn as points; the rows are those of the paper's Fig. 4.
panel = hht_figure(result, view="back")
