"""WGS-84 conversions, radar plot positioning and ellipsoidal distance against closed forms and hand work."""

import math

import numpy as np
import pytest

from msdc.pipeline.model.geodesy import (
    distance_m,
    ecef_to_enu,
    ecef_to_geodetic,
    enu_to_ecef,
    geodetic_to_ecef,
    plane_to_geodetic,
    polar_to_geodetic,
)

A = 6378137.0
F = 1 / 298.257223563
E2 = F * (2 - F)


def ecef(lat_deg, lon_deg, h_m):
    """Textbook closed form, written out here so the tests do not lean on the code under test."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    n = A / np.sqrt(1 - E2 * np.sin(lat) ** 2)
    return np.stack([(n + h_m) * np.cos(lat) * np.cos(lon), (n + h_m) * np.cos(lat) * np.sin(lon),
                     (n * (1 - E2) + h_m) * np.sin(lat)], -1)


def enu_axes(lat_deg, lon_deg):
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    east = np.array([-math.sin(lon), math.cos(lon), 0.0])
    north = np.array([-math.sin(lat) * math.cos(lon), -math.sin(lat) * math.sin(lon), math.cos(lat)])
    up = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    return east, north, up


def test_ecef_round_trip_is_submillimetre():
    rng = np.random.default_rng(7)
    lat, lon = rng.uniform(-89.9, 89.9, 5000), rng.uniform(-180, 180, 5000)
    h = rng.uniform(-500, 20000, 5000)
    xyz = ecef(lat, lon, h)
    assert np.allclose(np.stack(geodetic_to_ecef(lat, lon, h), -1), xyz, atol=1e-6, rtol=0)
    lat2, lon2, h2 = ecef_to_geodetic(xyz[:, 0], xyz[:, 1], xyz[:, 2])
    back = ecef(lat2, lon2, h2)
    assert np.max(np.linalg.norm(back - xyz, axis=1)) < 1e-3
    assert np.max(np.abs(h2 - h)) < 1e-3


def test_ecef_to_geodetic_known_points():
    b = A * (1 - F)
    lat, lon, h = ecef_to_geodetic(np.array([A, 0.0, A + 100]), np.array([0.0, 0.0, 0.0]),
                                   np.array([0.0, b + 50, 0.0]))
    assert lat == pytest.approx([0, 90, 0], abs=1e-9)
    assert h == pytest.approx([0, 50, 100], abs=1e-6)
    assert lon[0] == pytest.approx(0.0) and lon[2] == pytest.approx(0.0)


def test_enu_round_trip_and_axes():
    # 1000 m east of (0, 0, 0) is the ECEF point (a, 1000, 0)
    x, y, z = enu_to_ecef(1000.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert (x, y, z) == pytest.approx((A, 1000.0, 0.0), abs=1e-9)
    e, n, u = ecef_to_enu(x, y, z, 0.0, 0.0, 0.0)
    assert (e, n, u) == pytest.approx((1000.0, 0.0, 0.0), abs=1e-9)


@pytest.mark.parametrize("site_lat", [-60.0, -10.0, 0.0, 1.35, 45.0, 71.0])
def test_polar_round_trip_within_a_centimetre(site_lat):
    rng = np.random.default_rng(int(site_lat * 100) % 1000)
    site_lon, site_alt = 103.9, 25.0
    site = ecef(site_lat, site_lon, site_alt)
    east, north, up = enu_axes(site_lat, site_lon)
    # targets placed by a horizontal offset, then given a height of 0..45000 ft independently
    n = 400
    ground_m = rng.uniform(5, 250, n) * 1852.0
    az = rng.uniform(0, 360, n)
    h_m = rng.uniform(0, 45000, n) * 0.3048
    offset = (np.outer(ground_m * np.sin(np.radians(az)), east)
              + np.outer(ground_m * np.cos(np.radians(az)), north))
    tlat, tlon, _ = ecef_to_geodetic(*(site + offset).T)
    target = ecef(tlat, tlon, h_m)
    d = target - site
    rho_nm = np.linalg.norm(d, axis=1) / 1852.0
    theta = np.degrees(np.arctan2(d @ east, d @ north)) % 360
    ok = (rho_nm >= 5) & (rho_nm <= 250)
    lat, lon, h = polar_to_geodetic(site_lat, site_lon, site_alt, rho_nm[ok], theta[ok], h_m[ok])
    err_m = np.linalg.norm(ecef(lat, lon, h) - target[ok], axis=1)
    assert ok.sum() > 300
    assert err_m.max() < 0.01


def test_polar_hand_case_due_east_on_equator():
    # Site (0, 0, 0 m), azimuth 90, rho = 100 NM = 185200 m, target height 0: the plot lies on the
    # equator circle (radius a), so rho is a chord: lon = 2 asin(rho / 2a)
    # = 2 asin(185200 / 12756274) = 2 asin(0.0145183) = 1.66374 deg.
    lat, lon, h = polar_to_geodetic(0.0, 0.0, 0.0, 100.0, 90.0, 0.0)
    assert lat == pytest.approx(0.0, abs=1e-9)
    assert lon == pytest.approx(1.66374, abs=1e-5)
    assert h == pytest.approx(0.0, abs=1e-3)
    # same with h = 10000 m: law of cosines in the equatorial plane,
    # cos(lon) = (a^2 + (a+h)^2 - rho^2) / (2 a (a+h)) -> lon = 1.66001 deg
    _, lon, _ = polar_to_geodetic(0.0, 0.0, 0.0, 100.0, 90.0, 10000.0)
    assert lon == pytest.approx(1.66001, abs=1e-5)


def test_polar_hand_case_due_north_on_equator():
    # Site (0, 0, 0 m), azimuth 0, rho = 185200 m, h = 10000 m. Near the equator the meridian is its
    # osculating circle of radius M0 = a (1 - e^2) = 6335439.33 m, and geodetic latitude is the angle
    # at that circle's centre. Law of cosines: 1 - cos(lat) = (rho^2 - h^2) / (2 M0 (M0 + h))
    # = (3.429904e10 - 1e8) / (2 * 6335439.33 * 6345439.33) = 4.25349e-4 -> lat = 1.67119 deg.
    # The circle departs from the ellipse by ~1e-5 relative at this latitude, so allow 1e-4 deg.
    lat, lon, h = polar_to_geodetic(0.0, 0.0, 0.0, 100.0, 0.0, 10000.0)
    assert lon == pytest.approx(0.0, abs=1e-12)
    assert lat == pytest.approx(1.67119, abs=1e-4)
    assert h == pytest.approx(10000.0, abs=1e-3)
    # exact check: the point (N+h) cos lat, (N(1-e^2)+h) sin lat is at slant range rho from (a, 0, 0)
    p = ecef(lat, 0.0, 10000.0)
    assert math.hypot(p[0] - A, p[2]) == pytest.approx(185200.0, abs=1e-3)


def test_polar_unknown_height_uses_zero_elevation():
    lat, lon, h = polar_to_geodetic(1.35, 103.9, 20.0, np.array([60.0, 200.0]), np.array([30.0, 250.0]),
                                    np.array([np.nan, np.nan]))
    site = ecef(1.35, 103.9, 20.0)
    _, _, up = enu_axes(1.35, 103.9)
    d = ecef(lat, lon, h) - site
    assert np.abs(d @ up).max() < 1e-3  # on the site's horizontal plane
    assert np.linalg.norm(d, axis=1) == pytest.approx([60 * 1852.0, 200 * 1852.0], abs=1e-3)


def test_polar_out_of_reach_missing_and_broadcast():
    # 1 NM of slant range cannot reach 10 km above a site at 0 m: the nearest reachable point is straight
    # up (elevation 90 deg), 1852 m above the site; a missing range or azimuth places nothing
    rho = np.array([[1.0, np.nan, 100.0], [1.0, 100.0, 100.0]])
    theta = np.array([[0.0, 0.0, 90.0], [0.0, 90.0, np.nan]])
    lat, lon, h = polar_to_geodetic(0.0, 0.0, 0.0, rho, theta, np.array([10000.0, 0.0, 0.0]))
    assert lat.shape == lon.shape == h.shape == (2, 3)
    assert (lat[0, 0], lon[0, 0], h[0, 0]) == pytest.approx((0.0, 0.0, 1852.0), abs=1e-6)
    assert np.isnan([lat[0, 1], lon[0, 1], h[0, 1], lat[1, 2], lon[1, 2], h[1, 2]]).all()
    # the hand case due east above, in any cell it sits in
    assert lon[0, 2] == lon[1, 1] == pytest.approx(1.66374, abs=1e-5)
    scalar = polar_to_geodetic(0.0, 0.0, 0.0, 100.0, 90.0, 0.0)
    assert all(np.shape(v) == () for v in scalar)


def test_plane_to_geodetic():
    # x = y = 0 at height 3000 m: straight above the site
    lat, lon, h = plane_to_geodetic(1.35, 103.9, 20.0, 0.0, 0.0, 3000.0)
    assert (lat, lon, h) == pytest.approx((1.35, 103.9, 3000.0), abs=1e-7)
    # 10 NM east of (0, 0, 0) on the tangent plane is (a, 18520, 0): lon = atan(18520 / a)
    # = 0.166368 deg, height sqrt(a^2 + 18520^2) - a = 26.888 m
    lat, lon, h = plane_to_geodetic(0.0, 0.0, 0.0, 10.0, 0.0, np.nan)
    assert lat == pytest.approx(0.0, abs=1e-12)
    assert lon == pytest.approx(0.166368, abs=1e-6)
    assert h == pytest.approx(26.888, abs=1e-3)


def test_distance_hand_values():
    # along the equator the geodesic is the equator: 1 deg = a pi / 180 = 111319.491 m
    assert distance_m(0.0, 0.0, 0.0, 1.0) == pytest.approx(111319.491, abs=1e-3)
    # across the antimeridian
    assert distance_m(0.0, 179.5, 0.0, -179.5) == pytest.approx(111319.491, abs=1e-3)
    # meridian arc 0..1 deg: a (1 - e^2) * pi/180 * (1 + 1.5 e^2 <sin^2>) with <sin^2> ~ (pi/180)^2 / 3
    # = 6335439.33 * 0.0174533 * (1 + 1.0e-6) = 110574.39 m; check to 0.1 %
    assert distance_m(0.0, 0.0, 1.0, 0.0) == pytest.approx(110574.39, rel=1e-3)
    assert distance_m(51.0, 4.0, 51.0, 4.0) == 0.0


def test_distance_vectorised_and_symmetric():
    rng = np.random.default_rng(3)
    lat1, lon1 = rng.uniform(-60, 60, 100), rng.uniform(-180, 180, 100)
    lat2, lon2 = lat1 + rng.uniform(-1, 1, 100), lon1 + rng.uniform(-1, 1, 100)
    d12, d21 = distance_m(lat1, lon1, lat2, lon2), distance_m(lat2, lon2, lat1, lon1)
    assert np.allclose(d12, d21, rtol=1e-12)
    # the ECEF chord at zero height is shorter than the arc by about s^3 / (24 R^2), R >= 6.33e6 m
    chord = np.linalg.norm(ecef(lat1, lon1, 0.0) - ecef(lat2, lon2, 0.0), axis=1)
    assert np.all(d12 >= chord - 1e-6)
    assert np.all(d12 - chord <= d12**3 / (24 * 6.33e6**2) + 1e-3)
    assert np.isnan(distance_m(np.nan, 0.0, 0.0, 0.0))


def test_up_vector_is_the_ellipsoid_normal():
    from msdc.pipeline.model.geodesy import enu_basis, up_vector

    # by hand: on the equator at longitude 0 and 90 E the normal is the ECEF x and y axis; at a pole, z
    assert up_vector(0.0, 0.0).tolist() == [1.0, 0.0, 0.0]
    assert np.allclose(up_vector(0.0, 90.0), [0.0, 1.0, 0.0], atol=1e-16)
    assert np.allclose(up_vector(90.0, 33.0), [0.0, 0.0, 1.0], atol=1e-16)
    c = np.sqrt(0.5)  # 45 N 45 E: cos 45 cos 45, cos 45 sin 45, sin 45
    assert np.allclose(up_vector(45.0, 45.0), [0.5, 0.5, c], rtol=1e-15)
    rng = np.random.default_rng(11)  # and enu_basis's up to the bit, NaN where a coordinate is missing
    lat, lon = rng.uniform(-90, 90, 5000), rng.uniform(-400, 400, 5000)
    lat[::50] = np.nan
    assert np.array_equal(up_vector(lat, lon), enu_basis(lat, lon)[2], equal_nan=True)
