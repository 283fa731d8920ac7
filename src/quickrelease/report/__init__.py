"""Tables and figures for people: results drawn, never computed.

Modules, one question each (import them by their full path; this package imports none of them: matplotlib
loads only when a figure is asked for):

- :mod:`~quickrelease.report.display`: the names and rounded values of the tables (``label``, ``number``,
  ``summary_table``);
- :mod:`~quickrelease.report.plots`: the device's figures (the paper's Fig. 13-15, identification, energy);
- :mod:`~quickrelease.report.building_plots`: the building's figures (record and model, decay, loop);
- :mod:`~quickrelease.report.html`: the HTML report of a run (``render_report``);
- ``_style``: the house style of the figures.

A figure receives a result that carries everything it shows; the report imports no study and no command line
(the import-linter contract in ``pyproject.toml``).
"""
