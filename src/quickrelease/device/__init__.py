"""The device: what the pushing and quick-release device does after its fuse breaks (the paper's model).

Modules, one question each:

- :mod:`~quickrelease.device.parameters`: the device's data (Table 2), the presets, device files
  (``Device``, ``DEVICE_KEYS``, ``CHECK_KEYS``, ``load_device``, ``preset``, ``preset_names``, ``read_toml``);
- :mod:`~quickrelease.device.statics`: push force, fuse force, internal forces, stored energy (Eq. 1-2, Table 3);
- :mod:`~quickrelease.device.kinematics`: positions, velocities, accelerations of the members (Tables 4-5);
- :mod:`~quickrelease.device.dynamics`: the equation of motion, mass factor c, energies (Eq. 3-10);
- :mod:`~quickrelease.device.closed_form`: what follows without integrating (initial rate, final angle, limits);
- :mod:`~quickrelease.device.solvers`: one ``simulate`` over three methods (explicit, rk, energy);
- :mod:`~quickrelease.device.response`: the ``Response`` of a release;
- :mod:`~quickrelease.device.identify`: F1 and F2 from a stop (Eq. 11-13, Table 7);
- :mod:`~quickrelease.device.reference`: the mpmath reference; :mod:`~quickrelease.device.paper`: the paper's
  numbers beside ours; ``_kernels``: the scalar kernels the batch layer compiles.

The device's physics imports no files, tables, figures, studies or command line (the import-linter contract
in ``pyproject.toml``). The package re-exports the device data of :mod:`~quickrelease.device.parameters`.
"""

from __future__ import annotations

from .parameters import CHECK_KEYS, DEVICE_KEYS, Device, load_device, preset, preset_names, read_toml

__all__ = ["Device", "DEVICE_KEYS", "CHECK_KEYS", "load_device", "preset", "preset_names", "read_toml"]
