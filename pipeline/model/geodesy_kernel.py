"""Compiled per-plot kernels of `geodesy`: a radar plot's position solved one plot at a time, so that each
plot's Newton iteration stops when it has converged, with no (n, 3) temporaries per step."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .geodesy import _HEIGHT_TOL_M, _NEWTON_STEPS, A_M, B_M, E2, EP2


@njit(cache=True, nogil=True, error_model="numpy")
def _geodetic_terms(x_m: float, y_m: float, z_m: float) -> tuple[float, float, float]:
    """`geodesy.ecef_to_geodetic`'s closed form for one point, up to its last step: the distance from the
    axis p, the latitude's numerator w (latitude = atan2(w, p)) and the height."""
    p2 = x_m * x_m + y_m * y_m
    p = math.sqrt(p2)
    z2 = z_m * z_m
    f54 = 54.0 * B_M * B_M * z2
    g = p2 + (1.0 - E2) * z2 - E2 * (A_M * A_M - B_M * B_M)
    c = E2 * E2 * f54 * p2 / (g * g * g)
    s = np.cbrt(1.0 + c + math.sqrt(c * c + 2.0 * c))
    k = s + 1.0 + 1.0 / s
    pk = f54 / (3.0 * k * k * g * g)
    q = math.sqrt(1.0 + 2.0 * E2 * E2 * pk)
    root = 0.5 * A_M * A_M * (1.0 + 1.0 / q) - pk * (1.0 - E2) * z2 / (q * (1.0 + q)) - 0.5 * pk * p2
    r0 = -pk * E2 * p / (1.0 + q) + math.sqrt(max(root, 0.0))
    u = math.sqrt((p - E2 * r0) ** 2 + z2)
    v = math.sqrt((p - E2 * r0) ** 2 + (1.0 - E2) * z2)
    z0 = B_M * B_M * z_m / (A_M * v)
    return p, z_m + EP2 * z0, u * (1.0 - B_M * B_M / (A_M * v))


@njit(cache=True, nogil=True, error_model="numpy")
def _clipped(value: float, bound: float) -> float:
    """value within [-bound, bound]; NaN stays NaN (as numpy's clip)."""
    if value > bound:
        return bound
    if value < -bound:
        return -bound
    return value


@njit(cache=True, nogil=True, error_model="numpy")
def polar_plots(site_lat_deg, site_lon_deg, site_alt_m, rho_m, theta_deg, target_m, lat_deg, lon_deg, h_m):
    """`geodesy.polar_to_geodetic` over 1-D arrays of equal length, written into lat_deg, lon_deg, h_m."""
    half_pi = 0.5 * math.pi
    mean_radius = math.sqrt(A_M * B_M)
    for i in range(rho_m.shape[0]):
        la, lo, alt, r = math.radians(site_lat_deg[i]), math.radians(site_lon_deg[i]), site_alt_m[i], rho_m[i]
        sl, cl, so, co = math.sin(la), math.cos(la), math.sin(lo), math.cos(lo)
        n_m = A_M / math.sqrt(1.0 - E2 * sl * sl)
        sx, sy, sz = (n_m + alt) * cl * co, (n_m + alt) * cl * so, (n_m * (1.0 - E2) + alt) * sl
        th = math.radians(theta_deg[i])
        st, ct = math.sin(th), math.cos(th)
        hx, hy, hz = -st * so - ct * sl * co, st * co - ct * sl * so, ct * cl  # sin(t) east + cos(t) north
        ux, uy, uz = cl * co, cl * so, sl
        target = target_m[i]
        elev = 0.0
        if math.isfinite(target):  # Newton on the elevation, from the spherical law of cosines
            radius = mean_radius + alt
            sin_e = ((radius - alt + target) ** 2 - radius * radius - r * r) / (2.0 * radius * r)
            if math.isnan(sin_e):
                sin_e = 0.0
            elev = math.asin(min(max(sin_e, -1.0), 1.0))
            for _ in range(_NEWTON_STEPS):
                ce, se = math.cos(elev), math.sin(elev)
                px, py = sx + r * (ce * hx + se * ux), sy + r * (ce * hy + se * uy)
                pz = sz + r * (ce * hz + se * uz)
                p, w, ph = _geodetic_terms(px, py, pz)
                # the derivative of the point along the elevation, on the ellipsoid normal there: (cos lat
                # cos lon, cos lat sin lon, sin lat) = (x / d, y / d, w / d), d = hypot(p, w)
                d = math.hypot(p, w)
                slope = r * ((ce * ux - se * hx) * px + (ce * uy - se * hy) * py
                             + (ce * uz - se * hz) * w) / d
                err = ph - target
                step = err / slope if abs(slope) > 1e-9 else 0.0
                elev = _clipped(elev - step, half_pi)
                if not math.isfinite(err) or abs(err) < _HEIGHT_TOL_M:
                    break
        ce, se = math.cos(elev), math.sin(elev)
        px, py = sx + r * (ce * hx + se * ux), sy + r * (ce * hy + se * uy)
        p, w, h_m[i] = _geodetic_terms(px, py, sz + r * (ce * hz + se * uz))
        lat_deg[i], lon_deg[i] = math.degrees(math.atan2(w, p)), math.degrees(math.atan2(py, px))
