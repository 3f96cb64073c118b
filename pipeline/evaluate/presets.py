"""Presets: a standard's requirements as data (TOML files shipped in presets/, or a user's own file), read
into typed dataclasses with clear messages naming the file, the requirement and the key for bad input."""

from __future__ import annotations

import difflib
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from msdc.pipeline.evaluate.catalogue import CATALOGUE, ERROR, SIGNED
from msdc.pipeline.evaluate.statistics import DIRECTIONS

PRESET_KEYS = {"name": str, "title": str, "standard": str, "sensor_types": list, "source": str,
               "min_sample": int, "areas": dict, "note": str, "gate_m": float}
PRESET_REQUIRED = ("name", "title", "standard", "sensor_types", "source")
REQUIREMENT_KEYS = {"id": str, "threshold": float, "direction": str, "clause": str, "checked": bool,
                    "source": str, "stated": str, "area": str, "min_sample": int, "parameters": dict,
                    "note": str}
REQUIREMENT_REQUIRED = ("id", "threshold", "direction", "clause", "checked", "source", "stated")
SENSOR_TYPES = ("ssr", "mode_s", "psr", "mlat", "wam", "smr", "adsb", "tracker")
# the scorecard's own sector names: an area or sector named so would pass for them
RESERVED_SECTORS = ("global", "surface", "airborne", "field monitors")
MIN_INTERVAL_S = 0.1  # the shortest update interval a preset may ask for (an ADS-B report rate is 0.5 s)


@dataclass(frozen=True)
class Requirement:
    """One requirement: a documented id, its threshold and direction, parameters, and where it comes from.

    ``checked`` is False where the figure was not checked against the standard's own text (``source``
    says where it came from): such a figure is a configurable default, never "compliant with" the standard."""

    id: str
    threshold: float
    direction: str
    clause: str
    checked: bool
    source: str
    stated: str
    area: str | None = None
    min_sample: int | None = None
    parameters: dict[str, float | str] = field(default_factory=dict)
    note: str = ""


@dataclass(frozen=True)
class Preset:
    """A standard's requirements for one kind of sensor, with the areas (sector names) they apply to."""

    name: str
    title: str
    standard: str
    sensor_types: tuple[str, ...]
    source: str
    requirements: tuple[Requirement, ...]
    min_sample: int | None = None
    areas: dict[str, str] = field(default_factory=dict)
    note: str = ""
    path: str = ""
    gate_m: float | None = None  # the association gate (reference.DEFAULT_GATE_M when None)

    def association(self) -> dict[str, float]:
        """The parameters the association of reports with reference aircraft takes under this preset."""
        return {} if self.gate_m is None else {"gate_m": self.gate_m}

    def minimum_sample(self, requirement: Requirement) -> int | None:
        """The minimum sample that applies to a requirement: its own, else the preset's."""
        return requirement.min_sample if requirement.min_sample is not None else self.min_sample


def _preset_files() -> dict[str, resources.abc.Traversable]:
    """The shipped presets by name (the file name without .toml)."""
    folder = resources.files("msdc.pipeline.evaluate").joinpath("presets")
    return {f.name.removesuffix(".toml"): f for f in folder.iterdir() if f.name.endswith(".toml")}


def available_presets() -> list[str]:
    """The names of the presets shipped with msdc, sorted."""
    return sorted(_preset_files())


def _hint(word: str, choices) -> str:
    """' (did you mean X?)' when a close match exists, else ''."""
    near = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {near[0]!r}?)" if near else ""


def _typed(where: str, key: str, value, kind):
    """The value checked against its expected type (an int is accepted for a float, never a bool)."""
    if kind is float and isinstance(value, int | float) and not isinstance(value, bool):
        if not math.isfinite(value):
            raise ValueError(f"{where}: key {key!r} must be a finite number, got {value!r}")
        return float(value)
    if kind is int and isinstance(value, int) and not isinstance(value, bool):
        if value < 1:
            raise ValueError(f"{where}: key {key!r} must be a whole number >= 1, got {value!r}")
        return value
    if isinstance(kind, tuple):
        if value not in kind:
            raise ValueError(f"{where}: key {key!r} must be one of {', '.join(map(repr, kind))}, "
                             f"got {value!r}{_hint(str(value), kind)}")
        return value
    if kind not in (float, int) and isinstance(value, kind):
        return value
    name = {float: "a number", int: "a whole number", str: "text", bool: "true or false", list: "a list",
            dict: "a table"}[kind]
    raise ValueError(f"{where}: key {key!r} must be {name}, got {value!r} ({type(value).__name__})")


def _check_keys(where: str, table: dict, allowed: dict, required: tuple[str, ...]) -> None:
    """Refuse unknown keys (with a did-you-mean) and missing required keys."""
    for key in table:
        if key not in allowed:
            raise ValueError(f"{where}: unknown key {key!r}{_hint(key, allowed)}; "
                             f"known keys: {', '.join(allowed)}")
    missing = [k for k in required if k not in table]
    if missing:
        plural = "s" if len(missing) > 1 else ""
        raise ValueError(f"{where}: missing key{plural} {', '.join(map(repr, missing))}")


def _requirement(where: str, table, areas: dict[str, str]) -> Requirement:
    """One [[requirement]] table checked and typed."""
    if not isinstance(table, dict):
        raise ValueError(f"{where}: must be a table, got {table!r}")
    if "id" in table and table["id"] not in CATALOGUE:
        ident = table["id"]
        raise ValueError(f"{where}: unknown requirement id {ident!r}{_hint(str(ident), CATALOGUE)}; "
                         f"see docs/methods/evaluate.md for the documented ids")
    where = f"{where} ({table['id']})" if "id" in table else where
    _check_keys(where, table, REQUIREMENT_KEYS, REQUIREMENT_REQUIRED)
    values = {k: _typed(where, k, v, REQUIREMENT_KEYS[k]) for k, v in table.items()}
    if values["direction"] not in DIRECTIONS:
        raise ValueError(f"{where}: key 'direction' must be one of {', '.join(DIRECTIONS)}, "
                         f"got {values['direction']!r}")
    kind = CATALOGUE[values["id"]]
    if kind.kind in (ERROR, SIGNED) and not values["threshold"] > 0.0:
        raise ValueError(f"{where}: key 'threshold' must be a positive number of {kind.unit} for "
                         f"{values['id']}, got {values['threshold']!r}")
    if kind.unit == "fraction" and not 0.0 <= values["threshold"] <= 1.0:
        raise ValueError(f"{where}: key 'threshold' is a fraction between 0 and 1 for {values['id']}, "
                         f"got {values['threshold']!r} (write 97 % as 0.97)")
    params = values.get("parameters", {})
    _check_keys(f"{where} parameters", params, kind.parameters, kind.required)
    values["parameters"] = {k: _typed(f"{where} parameters", k, v, kind.parameters[k])
                            for k, v in params.items()}
    checked = values["parameters"]
    for key, value in checked.items():
        if isinstance(value, float) and value <= 0.0:
            raise ValueError(f"{where} parameters: key {key!r} must be > 0, got {value!r}")
    if checked.get("interval_s", MIN_INTERVAL_S) < MIN_INTERVAL_S:
        raise ValueError(f"{where} parameters: key 'interval_s' must be at least {MIN_INTERVAL_S:g} s, got "
                         f"{checked['interval_s']!r}")
    if checked.get("min_gap_s", 0.0) >= checked.get("max_gap_s", math.inf):
        raise ValueError(f"{where} parameters: min_gap_s {checked['min_gap_s']!r} must be below max_gap_s "
                         f"{checked['max_gap_s']!r} (the gaps counted are min_gap_s <= gap < max_gap_s)")
    if "area" in values and values["area"] not in areas:
        raise ValueError(f"{where}: key 'area' names {values['area']!r}, not among the preset's [areas] "
                         f"({', '.join(areas) or 'none declared'}){_hint(values['area'], areas)}")
    return Requirement(**values)


def _parse(label: str, text: str) -> Preset:
    """A preset from its TOML text (a leading byte-order mark allowed); label names the file in every
    message."""
    try:
        data = tomllib.loads(text.removeprefix("\ufeff"))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{label}: not valid TOML: {exc}") from None
    _check_keys(label, data, {"preset": dict, "requirement": list}, ("preset", "requirement"))
    head = data["preset"]
    if not isinstance(head, dict):
        raise ValueError(f"{label}: [preset] must be a table")
    _check_keys(f"{label} [preset]", head, PRESET_KEYS, PRESET_REQUIRED)
    meta = {k: _typed(f"{label} [preset]", k, v, PRESET_KEYS[k]) for k, v in head.items()}
    for kind in meta["sensor_types"]:
        if kind not in SENSOR_TYPES:
            raise ValueError(f"{label} [preset]: key 'sensor_types' holds {kind!r}"
                             f"{_hint(str(kind), SENSOR_TYPES)}; known types: {', '.join(SENSOR_TYPES)}")
    meta["sensor_types"] = tuple(meta["sensor_types"])
    if not meta["sensor_types"]:
        raise ValueError(f"{label} [preset]: key 'sensor_types' names no sensor type; known types: "
                         f"{', '.join(SENSOR_TYPES)}")
    if "gate_m" in meta and not meta["gate_m"] > 0.0:
        raise ValueError(f"{label} [preset]: key 'gate_m' must be a positive number of metres, "
                         f"got {meta['gate_m']!r}")
    areas = meta.get("areas", {})
    for area, description in areas.items():
        _typed(f"{label} [preset.areas]", area, description, str)
        if area in RESERVED_SECTORS:
            raise ValueError(f"{label} [preset.areas]: the area name {area!r} is the scorecard's own; "
                             f"{', '.join(map(repr, RESERVED_SECTORS))} cannot name an area")
    rows = data["requirement"]
    if not isinstance(rows, list) or not rows:
        raise ValueError(f"{label}: no [[requirement]] tables")
    requirements = tuple(_requirement(f"{label} requirement {i + 1}", row, areas)
                         for i, row in enumerate(rows))
    seen: dict[tuple, int] = {}
    for i, req in enumerate(requirements):
        key = (req.id, req.area, tuple(sorted(req.parameters.items())))
        if key in seen:
            raise ValueError(f"{label} requirement {i + 1} ({req.id}): repeats requirement {seen[key] + 1} "
                             f"(same id, area and parameters)")
        seen[key] = i
    return Preset(requirements=requirements, path=label, **meta)


def load_preset(name_or_path: str | Path) -> Preset:
    """A shipped preset by name (see available_presets()) or a user's TOML file by path."""
    files = _preset_files()
    name = str(name_or_path)
    if not name.strip():
        raise ValueError("the preset is empty: give a shipped preset's name or a .toml file's path")
    if name in files:
        return _parse(f"preset {name}", files[name].read_text(encoding="utf-8"))
    path = Path(name)
    if path.suffix == ".toml" or path.exists():
        if not path.is_file():
            why = "not a file" if path.exists() else "no such file"
            if path.stem in files:
                why += f" (the shipped preset is named {path.stem!r}, without .toml)"
            raise ValueError(f"preset file {path}: {why}")
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"preset file {path}: cannot be read ({exc})") from None
        return _parse(str(path), text)
    raise ValueError(f"unknown preset {name!r}{_hint(name, files)}: the shipped presets are "
                     f"{', '.join(sorted(files))}; or give the path of a .toml file")
