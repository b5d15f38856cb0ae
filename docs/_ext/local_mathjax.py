"""MathJax served by the site itself: the offline build copies it from an installed wheel.

Sphinx loads MathJax from a CDN by default, so a page with equations read offline (or behind a
firewall) shows raw TeX.  The ``docs`` extra installs ``django-static-mathjax``, a wheel of the
MathJax 3.2 release files (its import package ``mathjax`` holds them; Django is not needed),
and ``conf.py`` points ``mathjax_path`` at ``_static/mathjax/tex-mml-chtml.js``.  After the HTML
build, the combined script and the parts it loads on demand are copied there: the TeX
extensions ``autoload`` fetches, the CHTML fonts, and the menu's accessibility components.
"""

from __future__ import annotations

import shutil
from importlib.resources import files
from pathlib import Path

#: The MathJax ES5 build inside the installed wheel.
SOURCE = Path(str(files("mathjax"))) / "static" / "mathjax" / "es5"
#: The combined TeX/MathML-to-CHTML script, where ``conf.py``'s ``mathjax_path`` points.
SCRIPT = "tex-mml-chtml.js"
#: What the script loads relative to itself (sre, the speech engine, only when a reader turns speech on).
PARTS = (SCRIPT, "input", "output", "a11y", "ui", "adaptors", "sre")


def copy_mathjax(app, exception) -> None:
    """Copy :data:`PARTS` into ``_static/mathjax`` of a finished HTML build."""
    if exception is not None or app.builder.format != "html":
        return
    target = Path(app.outdir) / "_static" / "mathjax"
    target.mkdir(parents=True, exist_ok=True)
    for part in PARTS:
        source = SOURCE / part
        if source.is_dir():
            shutil.copytree(source, target / part, dirs_exist_ok=True)
        else:
            shutil.copy2(source, target / part)


def setup(app):
    app.connect("build-finished", copy_mathjax)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
