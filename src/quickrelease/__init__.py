"""quickrelease: dynamics of the pushing and quick-release device.

Implements Oliveto et al., "The dynamics of a pushing and quick release device for
dynamic testing of seismic isolated buildings": statics (Eq. 1-2, Table 3),
kinematics (Tables 4-5), release dynamics with lumped or distributed mass and
Coulomb friction (Eq. 3-10), three solvers (the paper's Table 6 scheme, Runge-Kutta,
the energy first integral) and the identification of the friction forces (Eq. 11-13,
Table 7). SI units throughout.
"""

from __future__ import annotations

from . import building
from ._threads import using_threads
from ._version import __version__
from .building import decay
from .building.isolation_fit import BuildingChannel, IsolationFit, compare_models, fit_isolation
from .building.model import FreeVibration, Isolation, TwoDOF, free_vibration
from .device import closed_form, dynamics, kinematics, statics
from .device.closed_form import (
    angular_acceleration,
    dissipated_energy,
    final_angle,
    friction_limits,
    initial_rate,
    kinetic_energy,
    reaches_geometric_limit,
)
from .device.dynamics import MASS_MODELS, mass_factor
from .device.identify import Identification, identify_friction, stop_time_on_line
from .device.parameters import DEVICE_KEYS, Device, load_device, preset, preset_names
from .device.response import STOP_REASONS, Response
from .device.solvers import METHODS, simulate, stop_time
from .device.statics import InternalForces, StrainEnergy, fuse_force, internal_forces, push_force, strain_energy
from .errors import (
    DeviceFileError,
    InfeasibleObservationError,
    ParameterError,
    QuickReleaseError,
    UnitError,
)
from .report import display as _display  # noqa: F401  (registers the results' repr and notebook tables)
from .units import parse_quantity

__all__ = [
    "DEVICE_KEYS", "Device", "load_device", "preset", "preset_names",
    "MASS_MODELS", "mass_factor", "angular_acceleration", "kinetic_energy", "initial_rate",
    "dissipated_energy", "final_angle", "reaches_geometric_limit", "friction_limits",
    "QuickReleaseError", "ParameterError", "DeviceFileError", "UnitError", "InfeasibleObservationError",
    "Identification", "identify_friction", "stop_time_on_line",
    "Response", "STOP_REASONS", "METHODS", "simulate", "stop_time",
    "InternalForces", "StrainEnergy", "fuse_force", "internal_forces", "push_force", "strain_energy",
    "parse_quantity", "closed_form", "dynamics", "kinematics", "statics", "__version__",
    "building", "decay", "Isolation", "TwoDOF", "FreeVibration", "free_vibration",
    "BuildingChannel", "IsolationFit", "fit_isolation", "compare_models", "using_threads",
]
