"""The sensor under test as the requirements see it (site, coverage limits, north markers), and whether a
reference aircraft is inside its coverage: the declared limits, else the limits of its own detections."""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from msdc.pipeline.evaluate.reference import DEFAULT_REFERENCE_GAP_S, checked_trajectories, rows_by_index
from msdc.pipeline.model.geodesy import slant_range_azimuth

LIMITS = ("min_range_nm", "max_range_nm", "min_elevation_deg", "max_elevation_deg")
SIGMAS = ("sigma_range_m", "sigma_azimuth_deg")


@dataclass(frozen=True)
class Sensor:
    """A sensor under test: its site, optional coverage limits (slant range, elevation; absent limits are
    estimated from its detections) and optional north-marker times (t_s) giving its scan period."""

    latitude: float
    longitude: float
    altitude_m: float
    name: str = ""
    min_range_nm: float | None = None
    max_range_nm: float | None = None
    min_elevation_deg: float | None = None
    max_elevation_deg: float | None = None  # above it: the cone of silence
    north_markers_s: np.ndarray | None = None
    sigma_range_m: float | None = None  # declared 1-sigma plot noise (radars): the bias fit's goodness of fit
    sigma_azimuth_deg: float | None = None
    # the scan period settled for the whole sensor and what it came from (detection.update_period): a
    # sector's requirements use it, where its own few plots would estimate another or none
    scan_period: tuple[float, str] | None = None
    # and its coverage, estimated once from all its associated reports (coverage_of): every requirement
    # and region then counts the same expected updates as inside
    settled_coverage: Coverage | None = None

    def __post_init__(self) -> None:
        for key in ("latitude", "longitude", "altitude_m", *LIMITS, *SIGMAS):
            v = getattr(self, key)
            number = isinstance(v, numbers.Real) and not isinstance(v, bool)
            if v is not None and (not number or not math.isfinite(v)):
                raise ValueError(f"sensor {self.name!r}: {key} must be a finite number, got {v!r}")

    def polar(self, lat_deg, lon_deg, h_m) -> tuple[np.ndarray, np.ndarray]:
        """Slant range (NM) and elevation (deg) of positions seen from the site."""
        rho, _, elev = self.polar_azimuth(lat_deg, lon_deg, h_m)
        return rho, elev

    def polar_azimuth(self, lat_deg, lon_deg, h_m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Slant range (NM), azimuth (deg from true north, 0-360) and elevation (deg) seen from the site."""
        rho, az, elev = slant_range_azimuth(self.latitude, self.longitude, self.altitude_m, lat_deg, lon_deg,
                                            h_m)
        return np.asarray(rho, float), np.asarray(az, float) % 360.0, np.asarray(elev, float)


@dataclass(frozen=True)
class Coverage:
    """Slant range and elevation limits, and where each came from (said in every result that uses them)."""

    min_range_nm: float
    max_range_nm: float
    min_elevation_deg: float
    max_elevation_deg: float
    source: str

    def inside(self, rho_nm: np.ndarray, elev_deg: np.ndarray) -> np.ndarray:
        """Whether positions (slant range, elevation) are inside the limits; NaN is outside."""
        rho, el = np.asarray(rho_nm, float), np.asarray(elev_deg, float)
        with np.errstate(invalid="ignore"):
            return ((rho >= self.min_range_nm) & (rho <= self.max_range_nm)
                    & (el >= self.min_elevation_deg) & (el <= self.max_elevation_deg))


def coverage(sensor: Sensor, detected_rho_nm: np.ndarray, detected_elev_deg: np.ndarray) -> Coverage:
    """The sensor's declared limits; an absent maximum range or elevation (the cone of silence) is estimated
    as the largest of the reference positions of its own associated detections, an absent minimum is none
    (0 NM, -90 deg: the lowest detections say little of a radar horizon, which falls with range);
    ``source`` says which limit came from where."""
    rho = np.asarray(detected_rho_nm, float)
    el = np.asarray(detected_elev_deg, float)
    rho, el = rho[np.isfinite(rho) & np.isfinite(el)], el[np.isfinite(rho) & np.isfinite(el)]
    estimate = {"min_range_nm": (lambda _: 0.0, None), "max_range_nm": (np.max, rho),
                "min_elevation_deg": (lambda _: -90.0, None), "max_elevation_deg": (np.max, el)}
    values, declared, estimated = {}, [], []
    for key, (fn, data) in estimate.items():
        given = getattr(sensor, key)
        if given is not None:
            values[key] = float(given)
            declared.append(f"{key} {given:g}")
        elif data is None:
            values[key] = float(fn(data))
        elif data.size:
            values[key] = float(fn(data))
            estimated.append(f"{key} {values[key]:.4g}")
        else:
            values[key] = math.nan
            estimated.append(f"{key} unknown (no detections)")
    parts = []
    if declared:
        parts.append("declared: " + ", ".join(declared))
    if estimated:
        parts.append("estimated from the sensor's own detections: " + ", ".join(estimated))
    return Coverage(**values, source="coverage " + "; ".join(parts))


def coverage_of(sensor: Sensor, reports, reference) -> Coverage:
    """The sensor's coverage from the reference positions at its associated reports (``ref_index`` >= 0):
    the limits ``coverage`` estimates where the sensor file declares none."""
    t, idx = reports["t_s"].to_numpy(float), reports["ref_index"].to_numpy()
    trajs = checked_trajectories(reference)[1] if len(reference) else []
    lat, lon, h = (np.full(len(reports), np.nan) for _ in range(3))
    for k, rows in enumerate(rows_by_index(idx, len(trajs))):
        if rows.size:
            lat[rows], lon[rows], h[rows], _ = trajs[k].at(t[rows], DEFAULT_REFERENCE_GAP_S)
    rho, elev = sensor.polar(lat, lon, h)
    return coverage(sensor, rho, elev)


def sensor_from_entry(entry: Mapping, north_markers_s: np.ndarray | None = None) -> Sensor:
    """The evaluation's Sensor of a sensor-table row (a row of read_sensors' table, or a dict): its site,
    name, the coverage limits it declares (absent or NaN: not declared, so estimated from its detections)
    and its plot noise sigmas where given."""
    def declared(key: str) -> float | None:
        v = entry.get(key)
        return None if v is None or (isinstance(v, numbers.Real) and math.isnan(v)) else float(v)

    return Sensor(float(entry["latitude"]), float(entry["longitude"]), float(entry["altitude_m"]),
                  name=str(entry["name"]), **{k: declared(k) for k in (*LIMITS, *SIGMAS)},
                  north_markers_s=north_markers_s)
