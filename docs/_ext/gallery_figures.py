"""The image scraper of the gallery (``docs/conf.py``): hht3d's figures are Matplotlib ``Figure`` objects made
without pyplot, which sphinx-gallery's own scraper does not see."""

from matplotlib.figure import Figure


def figure_scraper(block, block_vars, gallery_conf):
    """The Matplotlib ``Figure`` objects an example block left in its variables (hht3d's figures are made
    without pyplot, so the default scraper does not see them), each saved once, in order of creation."""
    from sphinx_gallery.scrapers import figure_rst

    shown = block_vars["example_globals"].setdefault("_scraped", set())
    paths = []
    for value in list(block_vars["example_globals"].values()):
        if isinstance(value, Figure) and id(value) not in shown:
            shown.add(id(value))
            path = next(block_vars["image_path_iterator"])
            value.savefig(path)
            paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
