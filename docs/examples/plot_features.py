"""
Prominent features
==================

A vertex that is a local extremum of many IMFs stands out at many scales: prominent features
are the vertices that are extrema of at least half of the IMFs (Sec. 5.2), with nearby hits
merged into one point.
"""

import hht3d
from hht3d.apps import FEATURE_EMD_OPTIONS, prominent_features
from hht3d.geometry import mean_curvature
from hht3d.viz import field_figure

surface = hht3d.load(hht3d.data_path("spot.ply"))
decomposition = hht3d.emd(surface, mean_curvature(surface), FEATURE_EMD_OPTIONS, max_imfs=3)
features = prominent_features(surface, decomposition)
print(
    f"{len(features.vertices)} feature points from {len(features.hits)} hits, each an extremum of >= "
    f"{features.min_count} of {decomposition.n_imfs} IMFs"
)

# %%
# How many scales each vertex is an extremum of; the feature points are where it is highest.
counts = field_figure(
    surface,
    features.vertex_counts.astype(float),
    title="extremum of how many IMFs",
    size=(500, 500),
    view="back",
    symmetric=False,
)
