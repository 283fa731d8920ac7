"""The building: the isolated building on its isolation layer, its free vibration, and its identification.

Modules, one question each:

- :mod:`~quickrelease.building.model`: the isolation models (linear, bilinear, two degrees of freedom) and
  their event-exact free vibration from the pushed state (``Isolation``, ``TwoDOF``, ``FreeVibration``,
  ``TwoDOFVibration``, ``free_vibration``, ``free_vibration_2dof``, ``pushed_state``, ``MODELS``,
  ``RECORD_CHANNELS``);
- :mod:`~quickrelease.building.hysteretic`: the isolation systems without a closed form, friction pendulum
  (Constantinou's mu(v)), Bouc-Wen bearings (lead-rubber, high-damping rubber) and power-law dampers
  (``Pendulum``, ``BoucWen``, ``HystereticVibration``), integrated by the event-located scheme of ``_ode``;
- :mod:`~quickrelease.building.flexible`: a flexible superstructure (2-DOF) on any of those isolation layers,
  hysteretic ones included (``FlexibleBuilding``, ``FlexibleVibration``, ``free_vibration_flexible``),
  integrated by the event-located scheme of ``_ode_flexible``;
- :mod:`~quickrelease.building.decay`: the decay of the free vibration (turning points, decrement laws,
  hysteresis loop; ``analyse_decay``);
- :mod:`~quickrelease.building.boucwen_loop`: Bouc-Wen isolators and dampers read off the measured loop by the
  equation error (``boucwen_loop``, ``BoucWenLoop``: the Bouc-Wen fit's start that depends on no basin);
- :mod:`~quickrelease.building.isolation_fit`: the isolation system fitted to records (``fit_isolation``,
  ``compare_models``, ``IsolationFit``, ``BuildingChannel``); ``isolation_search``: its global start search;
- :mod:`~quickrelease.building.identified`: whether a record identifies a fitted parameter (the one rule of the
  building's ``not_identified`` and of building campaigns; ``parameter_identified``);
- :mod:`~quickrelease.building.effective`: the quantities engineers report per cycle of an isolator's loop
  (keff, EDC, beta_eff, Qd, Kd, Teff, mu; ``loop_cycles``, ``CycleProperties``).

The building's physics imports no files, tables, figures, studies or command line (the import-linter contract
in ``pyproject.toml``). The package re-exports :mod:`~quickrelease.building.model`.
"""

from __future__ import annotations

from .flexible import FlexibleBuilding, FlexibleVibration, free_vibration_flexible
from .hysteretic import GRAVITY, BoucWen, HystereticVibration, Pendulum
from .model import (
    MODELS,
    RECORD_CHANNELS,
    FreeVibration,
    Isolation,
    TwoDOF,
    TwoDOFVibration,
    free_vibration,
    free_vibration_2dof,
    pushed_state,
)

__all__ = ["Isolation", "FreeVibration", "free_vibration", "pushed_state", "MODELS", "TwoDOF", "TwoDOFVibration",
           "free_vibration_2dof", "RECORD_CHANNELS", "Pendulum", "BoucWen", "HystereticVibration", "GRAVITY",
           "FlexibleBuilding", "FlexibleVibration", "free_vibration_flexible"]
