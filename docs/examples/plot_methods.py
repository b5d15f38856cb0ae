"""
Comparing the decomposition methods
===================================

``emd`` has two methods.  ``method="sifting"`` (the default, the paper's) subtracts the mean of
an upper and a lower envelope until an IMF is left; ``method="filtering"`` (iterative
filtering) takes each IMF as one fixed high-pass filter of the residue, whose cut comes from the
spacing of its extrema, and cannot cancel by construction.  Here both on spot's mean curvature,
then on a signal whose parts are known: the sum of two Laplacian eigenfunctions.
"""

import numpy as np
import scipy.sparse.linalg as spla
from matplotlib.figure import Figure

import hht3d
from hht3d.geometry import mean_curvature
from hht3d.viz.render import render

surface = hht3d.load(hht3d.data_path("spot.ply"))
curvature = mean_curvature(surface)
methods = ("sifting", "filtering")
results = {method: hht3d.emd(surface, curvature, method=method, max_imfs=3) for method in methods}

# %%
# The IMFs, finest first, one row per method; each panel has its own colour limits (robust
# percentiles, symmetric about 0).
imfs = Figure(figsize=(10, 6.2))
for row, method in enumerate(methods):
    for k, imf in enumerate(results[method].imfs):
        axes = imfs.add_subplot(2, 3, 3 * row + k + 1)
        axes.imshow(render(surface, imf, view="back", size=(300, 280)).rgba)
        axes.set_axis_off()
        axes.set_title(f"{method}: IMF {k + 1}", fontsize=10)
imfs.tight_layout()

# %%
# The quality figures of each: the energy ratio (1 when the parts add up to the signal's energy,
# above 1 when they cancel), the index of orthogonality IO (0 for orthogonal parts) and the
# energy share of each IMF.
print(f"{'method':<10} {'IMFs':>4} {'energy ratio':>13} {'IO':>7}  energy shares (IMFs, residue)")
for method, result in results.items():
    q = result.quality
    shares = " ".join(f"{x:.1%}" for x in q.energy_share)
    print(f"{method:<10} {result.n_imfs:>4} {q.energy_ratio:>13.3f} {q.orthogonality_index:>7.3f}  {shares}")

# %%
# A signal whose finer part is known: the eigenfunctions 3 and 40 of the generalized problem
# ``L φ = λ M φ`` (the surface's stiffness and mass), each scaled to a maximum of 1.  IMF 1
# should recover eigenfunction 40; the table gives the correlation of IMF 1 with it, for both
# signs of the finer part.
values, vectors = spla.eigsh(
    surface.stiffness, k=41, M=surface.mass, sigma=-1e-8, v0=np.ones(surface.n_vertices)
)  # shift-invert about 0: the lowest frequencies first; a fixed start vector fixes the signs
coarse, fine = (vectors[:, j] / np.abs(vectors[:, j]).max() for j in (3, 40))
print(f"eigenvalue ratio λ40 / λ3 = {values[40] / values[3]:.1f}")
first = {
    (method, sign): hht3d.emd(surface, coarse + sign * fine, method=method, max_imfs=2).imfs[0]
    for method in methods
    for sign in (1, -1)
}
print(f"{'method':<10} {'sign':>4}  |corr(IMF 1, eigenfunction 40)|")
for (method, sign), imf in first.items():
    print(f"{method:<10} {sign:>+4d}  {abs(np.corrcoef(imf, fine)[0, 1]):.3f}")

# %%
# The two parts and what each method's IMF 1 made of their sum (``+`` sign).
parts = Figure(figsize=(10, 3.4))
panels = [("eigenfunction 3", coarse), ("eigenfunction 40", fine)]
panels += [(f"{method}: IMF 1", first[method, 1]) for method in methods]
for k, (title, values_k) in enumerate(panels):
    axes = parts.add_subplot(1, 4, k + 1)
    axes.imshow(render(surface, values_k, view="back", size=(260, 240)).rgba)
    axes.set_axis_off()
    axes.set_title(title, fontsize=10)
parts.tight_layout()
