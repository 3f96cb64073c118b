"""Polygons of a GeoJSON file (``--area FILE.geojson``) and which positions lie inside them.

A GeoJSON position is ``[longitude, latitude]`` (RFC 7946, 3.1.1) and an edge is a straight line in
longitude/latitude (3.1.1 again: no great circle), so a point is inside by the even-odd rule over every
ring of a polygon (its holes too) in that plane. Polygons of a file are united: a point inside any one is
inside. Rings that cross the antimeridian are refused (their straight edges would go the long way round).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

POLYGON_TYPES = ("Polygon", "MultiPolygon")


@dataclass(frozen=True, eq=False)  # the same file read twice is two areas: compared by identity
class Polygons:
    """The polygons of one file: each a tuple of rings (the outer ring, then its holes), each ring an
    (n, 2) array of longitude, latitude in degrees, closed (first point repeated last)."""

    path: str
    polygons: tuple[tuple[np.ndarray, ...], ...]


def read_polygons(path: str | Path) -> Polygons:
    """The Polygon and MultiPolygon geometries of a GeoJSON file (a bare geometry, a Feature or a
    FeatureCollection); ValueError naming the file and what is wrong."""
    p = Path(path)
    doc = read_geojson(p)
    polygons: list[tuple[np.ndarray, ...]] = []
    for where, geometry in _geometries(doc, "the document"):
        kind = geometry.get("type") if isinstance(geometry, dict) else None
        if kind not in POLYGON_TYPES:
            raise ValueError(f"{p}: {where} is a {kind or 'non-geometry'}, not a Polygon or MultiPolygon")
        polygons += geometry_polygons(p, where, geometry)
    if not polygons:
        raise ValueError(f"{p}: no Polygon or MultiPolygon in it")
    return Polygons(str(p), tuple(polygons))


def read_geojson(path: Path) -> object:
    """The parsed JSON of a GeoJSON file; ValueError naming the file when it cannot be read or parsed."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ValueError(f"{path}: cannot be read ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a GeoJSON file (not UTF-8 text)") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not a GeoJSON file (JSON error at line {exc.lineno}, column {exc.colno}: "
                         f"{exc.msg})") from None
    except RecursionError:
        raise ValueError(f"{path}: not a GeoJSON file (nested too deeply to read)") from None


def geometry_polygons(path: Path, where: str, geometry: dict) -> list[tuple[np.ndarray, ...]]:
    """The polygons (each a tuple of closed rings) of a Polygon or MultiPolygon geometry; ValueError naming
    the file, ``where`` and the polygon and ring at fault."""
    kind = geometry.get("type")
    coords = geometry.get("coordinates")
    parts = [coords] if kind == "Polygon" else coords
    if not isinstance(parts, list) or not parts:
        raise ValueError(f"{path}: {where} has no coordinates")
    out = []
    for k, rings in enumerate(parts):
        name = where if kind == "Polygon" else f"{where}, polygon {k + 1}"
        out.append(_rings(path, name, rings))
    return out


def _geometries(doc: object, where: str):
    """(where, geometry) for each geometry of a GeoJSON document."""
    kind = doc.get("type") if isinstance(doc, dict) else None
    if kind == "FeatureCollection":
        features = doc.get("features")
        if not isinstance(features, list):
            raise ValueError(f"{where}: a FeatureCollection without a features list")
        for i, feature in enumerate(features):
            yield from _geometries(feature, f"feature {i + 1}")
    elif kind == "Feature":
        yield where, doc.get("geometry")
    else:
        yield where, doc


def _rings(path: Path, where: str, rings: object) -> tuple[np.ndarray, ...]:
    """A polygon's rings as closed (n, 2) float arrays; ValueError for a ring that is not one."""
    if not isinstance(rings, list) or not rings:
        raise ValueError(f"{path}: {where} has no ring")
    out = []
    for j, ring in enumerate(rings):
        name = f"{where}, ring {j + 1}"
        if not isinstance(ring, list) or not all(isinstance(q, list) and len(q) >= 2 and all(
                isinstance(v, int | float) and not isinstance(v, bool) for v in q[:2]) for q in ring):
            raise ValueError(f"{path}: {name}: positions must be [longitude, latitude] numbers")
        raised = next((q[2] for q in ring if len(q) > 2 and q[2] != 0), None)
        if raised is not None:  # read as two numbers, an altitude would seem to band the sector, and not
            raise ValueError(f"{path}: {name}: a position carries an altitude ({raised!r}); msdc reads "
                             "longitude and latitude only: give a flight-level band as the sector's min_fl "
                             "and max_fl (with --area: --fl)")
        xy = np.array([[float(q[0]), float(q[1])] for q in ring], dtype=float)
        if len(xy) < 3 or not np.isfinite(xy).all():
            raise ValueError(f"{path}: {name}: a ring needs at least 3 finite positions")
        if (np.abs(xy[:, 1]) > 90).any() or (np.abs(xy[:, 0]) > 180).any():
            raise ValueError(f"{path}: {name}: a position is off the Earth (longitude beyond 180 or latitude "
                             "beyond 90 degrees; GeoJSON gives longitude first)")
        if (np.abs(np.diff(xy[:, 0])) > 180).any():
            raise ValueError(f"{path}: {name}: an edge spans more than 180 degrees of longitude (the ring "
                             "crosses the antimeridian, which is not supported)")
        if not np.array_equal(xy[0], xy[-1]):
            xy = np.vstack([xy, xy[:1]])
        if len(np.unique(xy, axis=0)) < 3:
            raise ValueError(f"{path}: {name}: a ring needs at least 3 different positions (it encloses "
                             "nothing)")
        out.append(xy)
    return tuple(out)


def inside(polygons: Polygons, latitude, longitude) -> np.ndarray:
    """Per position, whether it lies inside any polygon (even-odd over its rings, straight edges in
    longitude/latitude); False where the position is NaN."""
    return inside_any(polygons.polygons, latitude, longitude)


def inside_any(polygons: tuple[tuple[np.ndarray, ...], ...], latitude, longitude) -> np.ndarray:
    """Per position, whether it lies inside any of the polygons (each a tuple of closed rings: the outer
    ring, then its holes); False where the position is NaN."""
    lat = np.asarray(latitude, dtype=float)
    lon = np.asarray(longitude, dtype=float)
    hit = np.zeros(lat.shape, bool)
    for rings in polygons:
        odd = np.zeros(lat.shape, bool)
        for ring in rings:
            odd ^= _crossings_odd(ring, lon, lat)
        hit |= odd
    return hit & np.isfinite(lat) & np.isfinite(lon)


def _crossings_odd(ring: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Whether a ray from each point towards +x crosses the ring's edges an odd number of times."""
    odd = np.zeros(x.shape, bool)
    for (x0, y0), (x1, y1) in zip(ring[:-1], ring[1:], strict=True):
        if y0 == y1:
            continue  # a horizontal edge: the half-open rule below never counts it
        spans = (y0 > y) != (y1 > y)
        with np.errstate(invalid="ignore", divide="ignore"):
            x_cross = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
        odd ^= spans & (x < x_cross)
    return odd


def bounds(polygons: Polygons) -> tuple[float, float, float, float]:
    """West, south, east, north of every ring (for messages)."""
    xy = np.vstack([r for rings in polygons.polygons for r in rings])
    return (float(xy[:, 0].min()), float(xy[:, 1].min()), float(xy[:, 0].max()), float(xy[:, 1].max()))


__all__ = ["Polygons", "bounds", "geometry_polygons", "inside", "inside_any", "read_geojson", "read_polygons"]
