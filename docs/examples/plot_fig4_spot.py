"""
The paper's Fig. 4 on spot
==========================

The mean curvature of the shipped cow (Eq. 24), decomposed into three IMFs and a residue, with
the instantaneous frequency (Eq. 23) and local amplitude (Eq. 21) of each IMF under it: the
layout of the paper's Fig. 4.
"""

import hht3d
from hht3d.geometry import mean_curvature
from hht3d.viz import hht_figure, spectrum_figure

surface = hht3d.load(hht3d.data_path("spot.ply"))
result = hht3d.hht(surface, mean_curvature(surface), max_imfs=3)
result

# %%
# Row 1: the model, the signal, the IMFs (finest first) and the residue; rows 2 and 3: the
# frequency and the amplitude of each IMF.
panel = hht_figure(result, view="back", signal_name="mean curvature")  # spot faces -z

# %%
# The marginal Hilbert spectrum ``h(ω)`` and each IMF's share of it: the finest IMF holds the
# highest frequencies, and the IMFs overlap in frequency, as in 1-D EMD.
spectrum = spectrum_figure(result, size=(1200, 420))
