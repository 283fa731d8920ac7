"""Files in and out: case files, records, exports and run folders.

Modules, one question each (import them by their full path; this package imports none of them, so that
``import quickrelease`` stays fast):

- :mod:`~quickrelease.io.case`: case files (TOML) of a test of the device (``load_case``, ``Case``);
- :mod:`~quickrelease.io.building_case`: the ``[building]`` part of a case file (``load_building``);
- :mod:`~quickrelease.io.records`: records of a release read from tables (``load_record``, ``Record``);
- :mod:`~quickrelease.io.timebase`: time columns and sampling of records;
- :mod:`~quickrelease.io.export`: JSON, CSV, NetCDF written atomically (``write_json``, ``write_csv``, ...);
- :mod:`~quickrelease.io.runfolder`: the output folder of a run, its manifest and provenance;
- :mod:`~quickrelease.io.frames`: results as pandas DataFrames and xarray Datasets.

Files read or written by name are checked by :mod:`quickrelease._files` (at the ground).
"""
