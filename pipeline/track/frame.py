"""The per-track plane: a WGS-84 stereographic projection centred on the track's first report.

Stereographic is conformal, so a local east/north covariance maps into the plane by one rotation (the
grid convergence) and one scale factor, both measured here from the projection itself.
"""

from __future__ import annotations

import numpy as np
from pyproj import Transformer

_DLAT_DEG = 1e-5  # finite-difference step for the local scale and convergence (about 1 m)


class Plane:
    """Geodetic <-> plane (east_m, north_m) around (lat0, lon0)."""

    def __init__(self, lat0_deg: float, lon0_deg: float) -> None:
        self.lat0_deg = float(lat0_deg)
        self.lon0_deg = float(lon0_deg)
        # a bare PROJ pipeline (degrees in, metres out): 100 times cheaper to build than from_crs
        self._fwd = Transformer.from_pipeline(
            "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad "
            f"+step +proj=stere +lat_0={self.lat0_deg!r} +lon_0={self.lon0_deg!r} +k=1 +ellps=WGS84")

    @classmethod
    def around(cls, lat_deg, lon_deg) -> Plane:
        """A plane centred on the median of the positions (an isolated garbage report cannot move it)."""
        lat = np.asarray(lat_deg, float)
        lon = np.asarray(lon_deg, float)
        lon_rel = (lon - lon[0] + 180.0) % 360.0 - 180.0  # continuous across the antimeridian
        lon0 = (float(np.median(lon_rel)) + lon[0] + 180.0) % 360.0 - 180.0
        return cls(float(np.median(lat)), lon0)

    def forward(self, lat_deg, lon_deg) -> tuple[np.ndarray, np.ndarray]:
        e, n = self._fwd.transform(np.asarray(lon_deg, float), np.asarray(lat_deg, float))
        return np.asarray(e, float), np.asarray(n, float)

    def inverse(self, east_m, north_m) -> tuple[np.ndarray, np.ndarray]:
        lon, lat = self._fwd.transform(np.asarray(east_m, float), np.asarray(north_m, float),
                                       direction="INVERSE")
        return np.asarray(lat, float), np.asarray(lon, float)

    def local_to_plane(self, lat_deg, lon_deg) -> np.ndarray:
        """Matrices M (..., 2, 2) with plane vector = M @ local (east, north) vector at each point."""
        lat = np.asarray(lat_deg, float)
        lon = np.asarray(lon_deg, float)
        e0, n0 = self.forward(lat, lon)
        e1, n1 = self.forward(lat + _DLAT_DEG, lon)
        # metres per degree of latitude (meridian radius of curvature, WGS-84)
        a, f = 6378137.0, 1.0 / 298.257223563
        e2 = f * (2.0 - f)
        s = np.sin(np.radians(lat))
        m_per_deg = np.radians(1.0) * a * (1.0 - e2) / (1.0 - e2 * s * s) ** 1.5
        de = (e1 - e0) / (_DLAT_DEG * m_per_deg)
        dn = (n1 - n0) / (_DLAT_DEG * m_per_deg)
        # a conformal map sends local north (0, 1) to (de, dn) and local east (1, 0) to (dn, -de)
        m = np.empty(lat.shape + (2, 2))
        m[..., 0, 0] = dn
        m[..., 0, 1] = de
        m[..., 1, 0] = -de
        m[..., 1, 1] = dn
        return m
