"""Studies: analyses over records, samples, grids and campaigns, built on the device and the building.

Modules, one question each (import them by their full path; this package imports none of them):

- :mod:`~quickrelease.studies.fit`: F1, F2 (and more) fitted to a record of one release (``fit_record``);
- :mod:`~quickrelease.studies.uq`: uncertainty of the identified friction by sampling (``run_uq``);
- :mod:`~quickrelease.studies.sweep`: grids of releases (``run_sweep``);
- :mod:`~quickrelease.studies.planning`: plan a test: fuse, angle, member checks, clearance (``plan_case``);
- :mod:`~quickrelease.studies.campaign`: friction laws over a campaign of device tests;
- :mod:`~quickrelease.studies.building_analysis`: the building's record analysed (``analyse_building``);
- :mod:`~quickrelease.studies.building_effective`: the identified isolator's keff, EDC, beta_eff and Teff against the
  cycle amplitude with 95% bands, and the cycles judged against them (``effective_curves``, ``judge_cycles``);
- :mod:`~quickrelease.studies.building_campaign`: the building's properties against amplitude over releases;
- :mod:`~quickrelease.studies.synth`: synthetic records of a case (``quickrelease synth``);
- :mod:`~quickrelease.studies.distributed`: the Dask runner; :mod:`~quickrelease.studies.bench`: the benchmark.
"""
