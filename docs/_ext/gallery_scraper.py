"""A sphinx-gallery image scraper for the package's figures.

quickrelease's figure functions return a :class:`matplotlib.figure.Figure` made without pyplot (so they
never touch the user's pyplot state), which the stock matplotlib scraper, looking at pyplot's figures,
does not see. This one saves every Figure a gallery block left in the example's variables (each once).
"""

from __future__ import annotations

_SEEN: dict[str, list] = {}


def figures_in_globals(block, block_vars, gallery_conf):
    from matplotlib._pylab_helpers import Gcf
    from matplotlib.figure import Figure
    from sphinx_gallery.scrapers import figure_rst

    seen = _SEEN.setdefault(str(block_vars["src_file"]), [])
    pyplot_figures = [m.canvas.figure for m in Gcf.get_all_fig_managers()]  # the matplotlib scraper's
    paths = []
    for value in list(block_vars["example_globals"].values()):
        if not isinstance(value, Figure) or any(value is f for f in seen + pyplot_figures):
            continue
        seen.append(value)
        path = next(block_vars["image_path_iterator"])
        value.savefig(path, dpi=110)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
