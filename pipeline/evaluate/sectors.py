"""Sector layers (``--sectors FILE.geojson``): named polygons, each belonging to one of a preset's areas (the
one its ``area`` property names, else the one of its own name), optionally limited to a flight-level band,
and which reports or reference samples lie in each.

Polygons follow the ``--area`` rules (pipeline.model.polygons: straight edges in longitude/latitude, holes
by the even-odd rule, rings across the antimeridian refused). A band is half-open, ``min_fl <= FL <
max_fl`` as the flight-level bands of pipeline.evaluate.bins; a position without a flight level is outside
every banded sector and inside an unbanded one."""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from msdc.pipeline.evaluate.presets import RESERVED_SECTORS
from msdc.pipeline.model.polygons import POLYGON_TYPES, geometry_polygons, inside_any, read_geojson

PROPERTIES = ("name", "area", "min_fl", "max_fl")


@dataclass(frozen=True, eq=False)  # holds arrays: compared by identity
class Sector:
    """One sector: its unique name, the preset area it belongs to (None: none), its polygons (each a tuple
    of closed (n, 2) longitude/latitude rings, the outer one first) and its flight-level band (None: open)."""

    name: str
    area: str | None
    polygons: tuple[tuple[np.ndarray, ...], ...]
    min_fl: float | None = None
    max_fl: float | None = None

    @property
    def banded(self) -> bool:
        """Whether the sector is limited in flight level."""
        return self.min_fl is not None or self.max_fl is not None


def _text(where: str, key: str, value, *, required: bool) -> str | None:
    """A text property: non-empty (surrounding blanks removed), or None when absent and not required."""
    if value is None and not required:
        return None
    if not isinstance(value, str) or not value.strip():
        got = "missing" if value is None else f"{value!r} ({type(value).__name__})"
        raise ValueError(f"{where}: property {key!r} must be a non-empty text, got {got}")
    return value.strip()


def _level(where: str, key: str, value) -> float | None:
    """A flight-level property: a finite number, or None when absent."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ValueError(f"{where}: property {key!r} must be a finite number (a flight level, e.g. 245), "
                         f"got {value!r} ({type(value).__name__})")
    return float(value)


def _check_keys(where: str, properties: dict) -> None:
    """Other properties are left alone (style keys of map editors), but a near miss of a known one is
    refused: a misspelt band would silently leave the sector unbanded."""
    for key in properties:
        if key in PROPERTIES or not isinstance(key, str):
            continue
        near = difflib.get_close_matches(key.lower(), PROPERTIES, n=1, cutoff=0.75)
        if near:
            raise ValueError(f"{where}: property {key!r} is not one msdc reads (did you mean {near[0]!r}?); "
                             f"the properties are {', '.join(PROPERTIES)}")


def _sector(path: Path, index: int, feature) -> Sector:
    """One Feature as a Sector; ValueError naming the file, the feature's number and name, and the fault."""
    where = f"{path}: feature {index}"
    if not isinstance(feature, dict) or feature.get("type") != "Feature":
        raise ValueError(f"{where}: not a GeoJSON Feature")
    properties = feature.get("properties")
    if properties is None:
        properties = {}
    if not isinstance(properties, dict):
        raise ValueError(f"{where}: 'properties' must be an object, got {properties!r}")
    name = properties.get("name")
    if isinstance(name, str) and name.strip():
        where = f"{where} ({name.strip()!r})"
    name = _text(where, "name", name, required=True)
    if name in RESERVED_SECTORS:
        raise ValueError(f"{where}: the name {name!r} is the scorecard's own; "
                         f"{', '.join(map(repr, RESERVED_SECTORS))} cannot name a sector")
    _check_keys(where, properties)
    area = _text(where, "area", properties.get("area"), required=False)
    min_fl = _level(where, "min_fl", properties.get("min_fl"))
    max_fl = _level(where, "max_fl", properties.get("max_fl"))
    if min_fl is not None and max_fl is not None and min_fl >= max_fl:
        raise ValueError(f"{where}: min_fl {min_fl:g} is not below max_fl {max_fl:g} (the band is "
                         "min_fl <= FL < max_fl)")
    geometry = feature.get("geometry")
    kind = geometry.get("type") if isinstance(geometry, dict) else None
    if kind not in POLYGON_TYPES:
        raise ValueError(f"{where}: its geometry is a {kind or 'non-geometry'}, not a Polygon or "
                         "MultiPolygon")
    polygons = geometry_polygons(path, where.removeprefix(f"{path}: "), geometry)
    return Sector(name, area, tuple(polygons), min_fl, max_fl)


def read_sectors(path: str | Path) -> list[Sector]:
    """The sectors of a GeoJSON FeatureCollection, in file order; ValueError naming the file, the feature
    (number from 1, and name) and what is wrong."""
    p = Path(path)
    doc = read_geojson(p)
    kind = doc.get("type") if isinstance(doc, dict) else None
    if kind != "FeatureCollection":
        raise ValueError(f"{p}: a sectors file is a GeoJSON FeatureCollection, this is "
                         f"{'a ' + kind if isinstance(kind, str) else 'not GeoJSON'}")
    features = doc.get("features")
    if not isinstance(features, list) or not features:
        raise ValueError(f"{p}: a FeatureCollection without features (each sector is one Feature)")
    sectors: list[Sector] = []
    first: dict[str, int] = {}
    for i, feature in enumerate(features, start=1):
        sector = _sector(p, i, feature)
        if sector.name in first:
            raise ValueError(f"{p}: feature {i} ({sector.name!r}): the name is already feature "
                             f"{first[sector.name]}'s; sector names must be unique")
        first[sector.name] = i
        sectors.append(sector)
    return sectors


def sector_mask(sector: Sector, latitude, longitude, flight_level=None) -> np.ndarray:
    """Per position, whether it lies in the sector: inside its polygons and, for a banded sector, with a
    flight level in min_fl <= FL < max_fl (None or NaN: outside a banded sector)."""
    hit = inside_any(sector.polygons, latitude, longitude)
    if not sector.banded:
        return hit
    if flight_level is None:
        return np.zeros(hit.shape, bool)
    fl = np.broadcast_to(np.asarray(flight_level, dtype=float), hit.shape)
    with np.errstate(invalid="ignore"):
        if sector.min_fl is not None:
            hit &= fl >= sector.min_fl
        if sector.max_fl is not None:
            hit &= fl < sector.max_fl
    return hit & np.isfinite(fl)


def area_of(sector: Sector) -> str:
    """The preset area a sector belongs to: its ``area`` property, else its name (a sector named "tma"
    without an area is the preset's area "tma")."""
    return sector.area if sector.area is not None else sector.name


def sectors_for_area(sectors: list[Sector], area: str) -> list[Sector]:
    """The sectors that belong to a preset area (area_of), in file order."""
    return [s for s in sectors if area_of(s) == area]


def check_preset_areas(preset, sectors: list[Sector]) -> list[str]:
    """Warnings for the preset's areas that no sector belongs to (their requirements are then not
    evaluated) and for sectors naming an area the preset does not declare."""
    warnings = []
    have = {area_of(s) for s in sectors}
    for area, description in preset.areas.items():
        if area in have:
            continue
        needs = [r.id for r in preset.requirements if r.area == area]
        ids = ", ".join(dict.fromkeys(needs))
        consequence = "no requirement of the preset uses it"
        if needs:
            plural = len(needs) != 1
            consequence = (f"its {len(needs)} requirement{'s' if plural else ''} ({ids}) "
                           f"{'are' if plural else 'is'} not evaluated")
        warnings.append(f"preset {preset.name}: no sector has area {area!r} ({description}): {consequence}")
    for sector in sectors:
        if sector.area is not None and sector.area not in preset.areas:
            known = ", ".join(preset.areas) or "none"
            warnings.append(f"sector {sector.name!r}: area {sector.area!r} is not one of preset "
                            f"{preset.name}'s areas ({known}): no area requirement applies to it")
    return warnings


def area_overlaps(masks: list[tuple[str, str, np.ndarray]], what: str = "reports") -> str:
    """A note when sectors of different areas overlap where positions lie (``masks``: per sector its name,
    its area and whether each position lies in it), or '': such positions are judged under both areas'
    requirements, which a standard's areas (manoeuvring area, apron, stands) are not meant to share."""
    pairs: dict[tuple[str, str], int] = {}
    both = None
    for i, (name_a, area_a, mask_a) in enumerate(masks):
        for name_b, area_b, mask_b in masks[i + 1:]:
            if area_a == area_b:
                continue
            shared = mask_a & mask_b
            if shared.any():
                key = (f"{name_a!r} ({area_a})", f"{name_b!r} ({area_b})")
                pairs[key] = int(shared.sum())
                both = shared if both is None else both | shared
    if both is None:
        return ""
    listed = "; ".join(f"{a} and {b}: {n:,}" for (a, b), n in sorted(pairs.items(), key=lambda kv: -kv[1]))
    return (f"sectors of different areas overlap where {int(both.sum()):,} of the {what} lie ({listed}): "
            "those are judged under both areas' requirements; draw the areas apart")


__all__ = ["PROPERTIES", "Sector", "area_of", "area_overlaps", "check_preset_areas", "read_sectors",
           "sector_mask", "sectors_for_area"]
