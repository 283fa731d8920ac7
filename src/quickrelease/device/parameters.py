"""The device: member masses, lengths, sections and materials (Table 2).

A :class:`Device` holds the data of Table 2 of the paper in SI units. The paper's
device ships as a preset (``data/devices/paper.toml``); users describe their own in
a TOML file with the same keys, each a bare SI number or a string with units::

    m1 = "0.57678 t"      # mass of one bar E1 (the device has four)
    A4 = "531 mm^2"       # fuse section

Every entry must be present and positive; unknown keys are errors.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import DeviceFileError, ParameterError
from ..units import parse_quantity

__all__ = ["Device", "DEVICE_KEYS", "CHECK_KEYS", "load_device", "preset", "preset_names", "read_toml"]

#: Table 2 key -> (quantity kind, description with unit).
DEVICE_KEYS: dict[str, tuple[str, str]] = {
    "m1": ("mass", "mass of one bar E1 (four in the device) [kg]"),
    "m2": ("mass", "mass of one head E2 (two in the device) [kg]"),
    "L1": ("length", "length of a bar E1, hinge to hinge [m]"),
    "L2": ("length", "length of a head E2 [m]"),
    "L3": ("length", "length of an element E3 (fuse lodging) [m]"),
    "L4": ("length", "length of the fuse E4 [m]"),
    "A1": ("area", "cross-section area of E1 [m^2]"),
    "A2": ("area", "cross-section area of E2 [m^2]"),
    "A3": ("area", "cross-section area of E3 [m^2]"),
    "A4": ("area", "cross-section area of the fuse E4 [m^2]"),
    "I2": ("second_moment", "second moment of area of E2 [m^4]"),
    "E": ("pressure", "elastic modulus [Pa]"),
    "G": ("pressure", "shear modulus [Pa]"),
    "kappa": ("dimensionless", "shear correction factor of E2 [-]"),
}

#: Optional keys for the member checks of test planning (:mod:`quickrelease.studies.planning`): key -> (quantity
#: kind, description with unit). Where absent, the check that needs it is skipped with a note.
CHECK_KEYS: dict[str, tuple[str, str]] = {
    "fy": ("pressure", "yield strength of the steel beams E1 and E2, unless fy1 or fy2 is given [Pa]"),
    "fy1": ("pressure", "yield strength of the bars E1 [Pa]"),
    "fy2": ("pressure", "yield strength of the heads E2 [Pa]"),
    "fy3": ("pressure", "yield strength of the fuse lodgings E3 [Pa]"),
    "I1": ("second_moment", "smallest second moment of area of a bar E1, for flexural buckling [m^4]"),
    "Lcr1": ("length", "buckling (effective) length of a bar E1; L1 when not given [m]"),
    "W2": ("section_modulus", "elastic section modulus of a head E2 for bending [m^3]"),
    "h2": ("length", "depth of a head E2 (W2 = I2 / (h2 / 2) when W2 is not given) [m]"),
}

_METADATA_KEYS = ("name", "description")


@dataclass(frozen=True)
class Device:
    """Geometry, masses and materials of a pushing and quick-release device (Table 2).

    All values in SI units. The elements are those of Fig. 6: four bars E1, two
    heads E2, two fuse lodgings E3 (massless) and the fuse E4 (massless).
    """

    m1: float
    """Mass of one bar E1 [kg] (Table 2: 0.57678 t)."""
    m2: float
    """Mass of one head E2 [kg]."""
    L1: float
    """Length of a bar E1 [m]."""
    L2: float
    """Length of a head E2 [m]."""
    L3: float
    """Length of an element E3 [m]."""
    L4: float
    """Length of the fuse E4 [m]."""
    A1: float
    """Section area of E1 [m^2]."""
    A2: float
    """Section area of E2 [m^2]."""
    A3: float
    """Section area of E3 [m^2]."""
    A4: float
    """Section area of the fuse E4 [m^2]."""
    I2: float
    """Second moment of area of E2 [m^4]."""
    E: float
    """Elastic modulus [Pa]."""
    G: float
    """Shear modulus [Pa]."""
    kappa: float
    """Shear correction factor of E2 [-]."""
    name: str = "custom"
    """A short name for reports."""
    fy: float | None = None
    """Yield strength of the beams E1 and E2 unless fy1 or fy2 is given [Pa] (member checks)."""
    fy1: float | None = None
    """Yield strength of the bars E1 [Pa]."""
    fy2: float | None = None
    """Yield strength of the heads E2 [Pa]."""
    fy3: float | None = None
    """Yield strength of the fuse lodgings E3 [Pa]."""
    I1: float | None = None
    """Smallest second moment of area of a bar E1 [m^4] (flexural buckling)."""
    Lcr1: float | None = None
    """Buckling length of a bar E1 [m]; L1 when not given."""
    W2: float | None = None
    """Elastic section modulus of a head E2 [m^3]."""
    h2: float | None = None
    """Depth of a head E2 [m] (gives W2 = I2 / (h2/2) when W2 is not given)."""

    def __post_init__(self) -> None:
        for key, (_kind, description) in DEVICE_KEYS.items():
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ParameterError(key, value, "the positive real numbers (a number is required)")
            if not math.isfinite(value) or value <= 0.0:
                unit = description.rsplit("[", 1)[1].rstrip("]")
                raise ParameterError(key, float(value), "(0, inf)", "" if unit == "-" else unit)
            object.__setattr__(self, key, float(value))
        for key in CHECK_KEYS:
            value = getattr(self, key)
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
                raise ParameterError(key, value, "(0, inf)")
            object.__setattr__(self, key, float(value))

    def yield_strength(self, member: int) -> float | None:
        """Yield strength of member E1, E2 or E3 (1, 2, 3) [Pa]: fy<member>, else (for the beams E1 and E2)
        fy, else None. The fuse lodgings E3 are bar stock of the fuse's own steel: only fy3 applies."""
        value = getattr(self, f"fy{member}")
        return value if value is not None or member == 3 else self.fy

    @property
    def mass_ratio(self) -> float:
        """m1 / m2, the ratio that enters Eq. 3-6 [-]."""
        return self.m1 / self.m2

    def to_dict(self) -> dict[str, Any]:
        """The device as a plain dict of SI floats (and its name)."""
        return asdict(self)

    def replace(self, **changes: float) -> Device:
        """A copy with some entries changed (validated again)."""
        data = {f.name: getattr(self, f.name) for f in fields(self)}
        unknown = set(changes) - set(data)
        if unknown:
            raise ParameterError("device key", ", ".join(sorted(unknown)), f"the keys {', '.join(DEVICE_KEYS)}")
        data.update(changes)
        return Device(**data)

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any], source: str = "<mapping>") -> Device:
        """Build a device from a mapping of Table 2 keys to numbers or quantity strings.

        Parameters
        ----------
        mapping : mapping
            Keys ``m1, m2, L1, L2, L3, L4, A1, A2, A3, A4, I2, E, G, kappa`` (all
            required) and optionally ``name`` and ``description``.
        source : str
            Where the mapping came from (a file name), used in error messages.

        Raises
        ------
        DeviceFileError
            For a missing, unknown or invalid entry; the message names ``source``
            and the key.
        """
        unknown = [k for k in mapping if k not in DEVICE_KEYS and k not in CHECK_KEYS and k not in _METADATA_KEYS]
        if unknown:
            raise DeviceFileError(
                f"{source}: unknown key {unknown[0]!r}; valid keys: {', '.join(DEVICE_KEYS)}, "
                + ", ".join(_METADATA_KEYS) + "; for member checks: " + ", ".join(CHECK_KEYS)
            )
        missing = [k for k in DEVICE_KEYS if k not in mapping]
        if missing:
            raise DeviceFileError(
                f"{source}: missing key {missing[0]!r} ({DEVICE_KEYS[missing[0]][1]})"
            )
        values: dict[str, Any] = {}
        for key, (kind, description) in DEVICE_KEYS.items():
            try:
                value = parse_quantity(mapping[key], kind, key)
            except ValueError as exc:
                raise DeviceFileError(f"{source}: {exc}") from None
            if not math.isfinite(value) or value <= 0.0:
                raise DeviceFileError(
                    f"{source}: {key} = {mapping[key]!r} must be positive ({description})"
                )
            values[key] = value
        for key, (kind, description) in CHECK_KEYS.items():
            if key not in mapping:
                continue
            try:
                value = parse_quantity(mapping[key], kind, key)
            except ValueError as exc:
                raise DeviceFileError(f"{source}: {exc}") from None
            if not math.isfinite(value) or value <= 0.0:
                raise DeviceFileError(f"{source}: {key} = {mapping[key]!r} must be positive ({description})")
            values[key] = value
        name = mapping.get("name", Path(source).stem if source != "<mapping>" else "custom")
        if not isinstance(name, str):
            raise DeviceFileError(f"{source}: name = {name!r} must be a string")
        return cls(**values, name=name)


def read_toml(path: Path, what: str, error: type[Exception]) -> dict[str, Any]:
    """Parse a TOML file; ``error`` (naming the file) when it cannot be read, is not a regular file of at most
    16 MiB (a device node, a FIFO), is not valid TOML or is nested too deeply to parse."""
    return read_toml_text(path, what, error)[0]


def read_toml_text(path: Path, what: str, error: type[Exception]) -> tuple[dict[str, Any], str]:
    """:func:`read_toml`, and the file's text as read (once)."""
    from .._files import TOML_MAX_BYTES, read_input

    raw = read_input(path, what, error, TOML_MAX_BYTES)
    text = ""
    try:
        text = raw.decode("utf-8")
        return tomllib.loads(text), text
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise error(f"{path}: not valid TOML ({exc}){_quoted_line(text, exc)}") from None
    except RecursionError:
        raise error(f"{path}: not valid TOML (nested too deeply to parse)") from None


def _quoted_line(text: str, exc: Exception) -> str:
    """``: line N reads '...'`` for a TOML error that names its line (tomllib's message gives the line and column
    only: a key defined twice is otherwise not named), else ""."""
    import re

    match = re.search(r"at line (\d+), column \d+", str(exc))
    lines = text.splitlines() if isinstance(text, str) else []
    if match is None or not 1 <= int(match[1]) <= len(lines):
        return ""
    line = lines[int(match[1]) - 1].strip()
    return f": line {match[1]} reads {line[:80]!r}" if line else ""


def load_device(path: str | Path) -> Device:
    """Load a device from a TOML file whose keys are Table 2's symbols.

    Raises
    ------
    DeviceFileError
        When the file cannot be read, is not valid TOML, or an entry is missing,
        unknown or not positive.
    """
    path = Path(path)
    mapping = read_toml(path, "device file", DeviceFileError)
    return Device.from_mapping(mapping, source=str(path))


def preset_names() -> list[str]:
    """Names of the devices shipped with quickrelease."""
    folder = resources.files("quickrelease") / "data" / "devices"
    return sorted(p.name.removesuffix(".toml") for p in folder.iterdir() if p.name.endswith(".toml"))


@lru_cache(maxsize=16)
def preset(name: str = "paper") -> Device:
    """A device shipped with quickrelease; ``"paper"`` is the device of Table 2."""
    names = preset_names()
    if name not in names:
        raise ParameterError("preset", name, f"the presets {', '.join(names)}")
    resource = resources.files("quickrelease") / "data" / "devices" / f"{name}.toml"
    mapping = tomllib.loads(resource.read_text(encoding="utf-8"))
    return Device.from_mapping(mapping, source=f"preset:{name}")
