"""A sphinx-gallery image scraper for figures that pyplot does not manage.

clearsweep builds its figures on ``matplotlib.figure.Figure`` directly (no pyplot, no
global state), so sphinx-gallery's matplotlib scraper, which asks pyplot for its open
figures, sees none of them. This scraper saves every ``Figure`` that a block of an
example bound to a name and that no earlier block saved, in the order of binding.
"""

from __future__ import annotations

from pathlib import PurePosixPath

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst

_SAVED = "_gallery_saved"


def scrape_figures(block, block_vars, gallery_conf, **kwargs) -> str:
    """Save the example's new ``Figure`` objects; return the reST that shows them."""
    paths = []
    figures = [v for v in block_vars["example_globals"].values()
               if isinstance(v, Figure) and not getattr(v, _SAVED, False)]
    for fig, path in zip(figures, block_vars["image_path_iterator"]):
        fig.savefig(str(path), dpi=80)
        setattr(fig, _SAVED, True)
        paths.append(PurePosixPath(path))
    return figure_rst(paths, gallery_conf["src_dir"])
