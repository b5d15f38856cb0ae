"""Sphinx configuration of the hht3d documentation site (``bash .ci/docs``; ``docs`` extra).

The build is offline: no intersphinx, plotly.js comes from the installed package, MathJax from
the ``django-static-mathjax`` wheel (``_ext/local_mathjax.py``), no page loads anything from
another host (tests/test_site.py), and every gallery example runs on the shipped models.
"""

import sys
from pathlib import Path

import matplotlib

import hht3d

matplotlib.use("Agg")
sys.path.insert(
    0, str(Path(__file__).parent / "_ext")
)  # gallery_figures (the scraper of hht3d's figures), benchmark_pages


project = "hht3d"
author = "The hht3d developers"
copyright = "The hht3d developers, MIT licence"
release = version = hht3d.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "benchmark_pages",  # docs/benchmarks/*.md from benchmarks/results/*.json
    "local_mathjax",  # MathJax copied into _static/mathjax, not loaded from a CDN
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "_ext", "examples", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip"]

mathjax_path = "mathjax/tex-mml-chtml.js"  # relative to _static: local_mathjax.SCRIPT

myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

autosummary_generate = True
autodoc_typehints = "none"  # the numpydoc Parameters say the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "show_memory": False,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "image_scrapers": ("gallery_figures.figure_scraper",),
    "capture_repr": ("_repr_html_", "__repr__"),
    "write_computation_times": False,  # its pages load jQuery and DataTables from CDNs
}

html_theme = "pydata_sphinx_theme"
html_title = f"hht3d {release}"
# The theme's colour mode when the reader has chosen none; without it the theme logs a console error.
html_context = {"default_mode": "auto"}
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
