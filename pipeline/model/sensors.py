"""The sensor table: read ``[[sensor]]`` entries from TOML, look up each radar plot's site, and print the
entry a missing radar needs.

An entry is a radar (CAT048, the default) or the reference point of a multilateration system or a surface
movement radar (``category = 10`` or ``20`` with ``kind = "mlat"`` or ``"smr"``): the point their
Cartesian x/y are measured from (pipeline.model.multilateration places those reports).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.model.sources import pair_codes

REQUIRED_COLUMNS = ["name", "sac", "sic", "latitude", "longitude", "altitude_m"]
# Optional per-radar measurement noise (1 sigma), used for the position covariance of its plots.
DEFAULT_SIGMA_RANGE_M = 70.0
DEFAULT_SIGMA_AZIMUTH_DEG = 0.08
OPTIONAL_DEFAULTS = {"sigma_range_m": DEFAULT_SIGMA_RANGE_M, "sigma_azimuth_deg": DEFAULT_SIGMA_AZIMUTH_DEG}
RADAR_COLUMNS = [*REQUIRED_COLUMNS, *OPTIONAL_DEFAULTS]  # a radar entry, as sensor_sites gives it
# Which sensor an entry describes: its category and sensor kind (CAT048 radars by default; a CAT010 entry
# names its kind, which its reports' I010/020 TYP selects; CAT020 reports are all multilateration), and,
# for a reference point, the 1-sigma position error per axis of its reports that carry no I010/500 or
# I020/500 (NaN: none given)
KIND_COLUMNS = ["category", "kind", "sigma_m"]
# Optional declared coverage of a radar or surface radar (slant range from the site, elevation seen from it;
# above max_elevation_deg: the cone of silence), used by the evaluation (msdc.pipeline.evaluate.coverage);
# NaN where not given: the evaluation then estimates that limit from the sensor's own detections
COVERAGE_COLUMNS = ["min_range_nm", "max_range_nm", "min_elevation_deg", "max_elevation_deg"]
SENSOR_COLUMNS = [*RADAR_COLUMNS, *KIND_COLUMNS, *COVERAGE_COLUMNS]
RADAR_CATEGORY = 48
KINDS_OF = {48: ("radar",), 10: ("mlat", "smr"), 20: ("mlat",)}  # the kinds an entry of a category may be
# A CAT010 reference point without sigma_m: the A-SMGCS surveillance requirement (ICAO Doc 9830, EUROCAE
# ED-116 for surface radar, ED-117 for multilateration: 7.5 m at 95 %) as a circular Gaussian's per-axis
# sigma, 7.5 / 2.4477 = 3.06 m. A requirement, not a measurement: give sigma_m from the system's figures.
# CAT020 (wide-area multilateration too, whose accuracy varies by kilometres) has no default.
SMGCS_95_M = 7.5
DEFAULT_SIGMA_M = {10: SMGCS_95_M / math.sqrt(-2.0 * math.log(0.05))}
_NUMBER = (int, float)
_TYPES = {"name": (str,), "sac": (int,), "sic": (int,), "latitude": _NUMBER, "longitude": _NUMBER,
          "altitude_m": _NUMBER, "sigma_range_m": _NUMBER, "sigma_azimuth_deg": _NUMBER, "category": (int,),
          "kind": (str,), "sigma_m": _NUMBER, **dict.fromkeys(COVERAGE_COLUMNS, _NUMBER)}
# altitude_m: the geometry needs a finite height; past +-100 km it is no radar site (a plausible range,
# SITE_ALTITUDE_RANGE_M, only warns: implausible_altitudes)
_RANGES = {"sac": (0, 255), "sic": (0, 255), "latitude": (-90.0, 90.0), "longitude": (-180.0, 180.0),
           "altitude_m": (-100_000.0, 100_000.0), "sigma_range_m": (0.001, 10_000.0),
           "sigma_azimuth_deg": (0.0001, 10.0), "sigma_m": (0.01, 100_000.0),
           # no radar sees past 1,000 NM (the longest over-the-horizon ones are HF, not ASTERIX sources)
           "min_range_nm": (0.0, 1000.0), "max_range_nm": (0.0, 1000.0),
           "min_elevation_deg": (-90.0, 90.0), "max_elevation_deg": (-90.0, 90.0)}
SITE_ALTITUDE_RANGE_M = (-500.0, 6000.0)  # outside: almost certainly a wrong sensor file entry
# A SAC/SIC not in the sensor file is taken for damage (its records left out, with a warning) when it has
# fewer than max(STRAY_RADAR_RECORDS, STRAY_RADAR_SHARE x the CAT048 records) records: one damaged byte of
# I048/010 makes one such record, and a second hit landing on the same wrong pair is rare (a flipped bit
# gives one of 16 pairs), so 1-2 records are damage at any size; heavy damage spreads its phantoms over
# many pairs, each well under 0.1 % of the records. A real radar turns in 4-12 s, so one aircraft in its
# cover for a minute already makes 5-15 plots, and radars recorded together share the traffic, each
# holding a large part of the plots: such a radar still stops the run with the sensor-file lines to add.
# Size limits (docs/guide/sensors.md): a sensor file of up to 1 MiB holds thousands of [[sensor]] entries
# (one takes about 200 bytes); a name labels figures, workbook rows and messages, and one of 100 characters
# says what any radar is. Past them the file is refused, naming the limit: no run copies a name per plot
# (names are categorical), but a megabyte of name in a figure title or a message helps nobody.
SENSOR_FILE_MAX_BYTES = 1 << 20
NAME_MAX_CHARS = 100
STRAY_RADAR_RECORDS = 3
STRAY_RADAR_SHARE = 0.001


class UnknownRadar(ValueError):
    """Radar reports come from SAC/SIC pairs that the sensor table does not list."""

    def __init__(self, missing: list[tuple[int, int]]):
        self.missing = missing
        pairs = ", ".join(f"SAC {sac} SIC {sic}" for sac, sic in missing)
        snippets = "\n".join(sensor_toml_snippet(sac, sic) for sac, sic in missing)
        super().__init__(f"radar {pairs} not in the sensor table; add:\n{snippets}")


def _check_entry(path: Path, i: int, entry: object) -> dict:
    where = f"{path}: [[sensor]] entry {i + 1}"
    if not isinstance(entry, dict):
        raise ValueError(f"{where} is not a table")
    unknown = [k for k in entry if k not in SENSOR_COLUMNS]
    if unknown:  # a misspelt optional key would silently leave its default in place
        import difflib

        near = difflib.get_close_matches(unknown[0], SENSOR_COLUMNS, n=1)
        hint = f"did you mean {near[0]}? " if near else ""
        raise ValueError(f"{where}: unknown key {unknown[0]!r} ({hint}allowed: {', '.join(SENSOR_COLUMNS)})")
    missing = [k for k in REQUIRED_COLUMNS if k not in entry]
    if missing:
        raise ValueError(f"{where} lacks {', '.join(missing)} (needs {', '.join(REQUIRED_COLUMNS)})")
    entry = _kind_of(where, entry)
    for key, types in _TYPES.items():
        value = entry[key]
        if value is None:  # an optional key that does not apply to this kind of sensor
            continue
        if isinstance(value, bool) or not isinstance(value, types):
            kind = " or ".join("integer" if t is int else "float" if t is float else "string" for t in types)
            article = "an" if kind[0] in "aeiou" else "a"
            raise ValueError(f"{where}: {key} = {_as_toml(value)} should be {article} {kind}")
    if not entry["name"].strip():  # it labels the radar's rows: a blank one labelled them with nothing
        raise ValueError(f"{where} (SAC {entry['sac']} SIC {entry['sic']}): name is empty; give the sensor "
                         "a name (it labels figures, workbook rows and messages)")
    if len(entry["name"]) > NAME_MAX_CHARS:
        raise ValueError(f"{where} (SAC {entry['sac']} SIC {entry['sic']}): name is {len(entry['name']):,} "
                         f"characters long; a name may have up to {NAME_MAX_CHARS} (it labels figures, "
                         "workbook rows and messages)")
    for key, (lo, hi) in _RANGES.items():
        if entry[key] is not None and not lo <= entry[key] <= hi:  # (NaN is outside too)
            raise ValueError(f"{where} ({entry['name']!r}, SAC {entry['sac']} SIC {entry['sic']}): {key} = "
                             f"{entry[key]!r} is outside {lo}..{hi}")
    _check_coverage(where, entry)
    if entry["latitude"] == 0 and entry["longitude"] == 0:
        what = ("radar site" if entry["kind"] == "radar" else
                f"{KIND_NOUN[entry['kind']]} reference point")
        raise ValueError(f"{where} ({entry['name']!r}, SAC {entry['sac']} SIC {entry['sic']}): latitude 0, "
                         f"longitude 0 is no {what} (it is the TODO template msdc prints for a missing "
                         "sensor, or a missing value; every report would land at 0 N 0 E): give its "
                         "WGS-84 position")
    return {k: entry[k] for k in SENSOR_COLUMNS}


def _check_coverage(where: str, entry: dict) -> None:
    """Refuse coverage limits whose minimum is not below their maximum, or a maximum range of 0 (no position
    would be inside)."""
    if entry["max_range_nm"] is not None and not entry["max_range_nm"] > 0.0:
        raise ValueError(f"{where} ({entry['name']!r}): max_range_nm = {entry['max_range_nm']!r}: no "
                         "position would be inside the coverage")
    for lo, hi in (("min_range_nm", "max_range_nm"), ("min_elevation_deg", "max_elevation_deg")):
        if entry[lo] is not None and entry[hi] is not None and not entry[lo] < entry[hi]:
            raise ValueError(f"{where} ({entry['name']!r}): {lo} = {entry[lo]!r} is not below {hi} = "
                             f"{entry[hi]!r}: no position would be inside the coverage")


def _toml(path: Path) -> dict:
    """The TOML document of a sensor file of up to SENSOR_FILE_MAX_BYTES, a UTF-8 byte order mark (Windows
    Notepad writes one) skipped; ValueError naming the file and the reason otherwise."""
    with path.open("rb") as fh:
        data = fh.read(SENSOR_FILE_MAX_BYTES + 1)
    if len(data) > SENSOR_FILE_MAX_BYTES:
        raise ValueError(f"{path}: larger than {SENSOR_FILE_MAX_BYTES:,} bytes, the limit of a sensor file "
                         "(a [[sensor]] entry takes about 200 bytes): is it the sensor file?")
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: byte {exc.start} is not UTF-8 ({exc.reason})") from exc
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from exc
    except RecursionError:
        raise ValueError(f"{path}: arrays or inline tables nested too deeply to read (a sensor file needs "
                         "no nesting: [[sensor]] tables of plain keys)") from None


KIND_NOUN = {"radar": "radar", "mlat": "multilateration", "smr": "surface movement radar"}


def _as_toml(value: object) -> str:
    """A value as TOML writes it (true, not Python's True), for messages about the file."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def _kind_of(where: str, entry: dict) -> dict:
    """The entry with its category (48 when not given) and kind checked, and the optional keys of its kind
    filled: a radar's range and azimuth sigmas (defaults), a reference point's sigma_m (CAT010's default,
    else None); ValueError for a key that does not apply to the kind, or a kind the category cannot be."""
    category = entry.get("category", RADAR_CATEGORY)
    if isinstance(category, bool) or not isinstance(category, int) or category not in KINDS_OF:
        raise ValueError(f"{where}: category = {category!r} should be one of "
                         f"{', '.join(str(c) for c in KINDS_OF)} (48 radar, 10 surface movement, 20 "
                         "multilateration)")
    kinds = KINDS_OF[category]
    kind = entry.get("kind", kinds[0] if len(kinds) == 1 else None)
    if kind not in kinds:
        choice = " or ".join(repr(k) for k in kinds)
        said = f"kind = {kind!r}" if "kind" in entry else "no kind"
        raise ValueError(f"{where}: {said}; a CAT{category:03d} entry is {choice}"
                         + (" (which of the category's reports it places: I010/020 TYP 0, 1, 5 mlat, 3 smr)"
                            if category == 10 else ""))
    radar = kind == "radar"
    wrong = [k for k in (("sigma_m",) if radar else tuple(OPTIONAL_DEFAULTS)) if k in entry]
    if wrong:
        takes = "sigma_range_m and sigma_azimuth_deg" if radar else "sigma_m"
        raise ValueError(f"{where}: {wrong[0]} does not apply to a {KIND_NOUN[kind]} entry (it takes "
                         f"{takes})")
    if kind == "mlat":  # its reference point is the origin of x/y, not a site that ranges are measured from
        wrong = [k for k in COVERAGE_COLUMNS if k in entry]
        if wrong:
            raise ValueError(f"{where}: {wrong[0]} does not apply to a multilateration entry (its reference "
                             "point is the origin of its x/y, not a site whose range or elevation limits "
                             "its coverage)")
    fill = OPTIONAL_DEFAULTS | {"sigma_m": None} if radar else dict.fromkeys(OPTIONAL_DEFAULTS) | {
        "sigma_m": DEFAULT_SIGMA_M.get(category)}
    fill |= dict.fromkeys(COVERAGE_COLUMNS)
    return fill | entry | {"category": category, "kind": kind}


def read_sensors(path: str | Path) -> pd.DataFrame:
    """The sensor table (SENSOR_COLUMNS) of a TOML file; ValueError naming the file and entry if bad.

    The file may have up to SENSOR_FILE_MAX_BYTES, a name up to NAME_MAX_CHARS characters (the table's
    ``name`` is categorical: a name is never copied per report). Latitude/longitude are WGS-84 degrees
    (exactly 0 N 0 E, the printed template's value, is refused),
    altitude_m the antenna height above the WGS-84 ellipsoid; sigma_range_m and sigma_azimuth_deg (optional,
    defaults 70 m and 0.08 deg) the 1-sigma plot noise; COVERAGE_COLUMNS the optional declared coverage of
    a radar or surface radar (NaN when not given).
    """
    path = Path(path)
    doc = _toml(path)
    entries = doc.get("sensor")
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{path}: no [[sensor]] tables found")
    rows = [_check_entry(path, i, e) for i, e in enumerate(entries)]
    seen: dict[tuple[int, str, int, int], str] = {}
    for row in rows:
        key = (row["category"], row["kind"], row["sac"], row["sic"])
        if key in seen:
            what = "" if row["kind"] == "radar" else f"CAT{key[0]:03d} {key[1]} "
            raise ValueError(f"{path}: {what}SAC {key[2]} SIC {key[3]} appears twice "
                             f"({seen[key]!r} and {row['name']!r})")
        seen[key] = row["name"]
    return _typed(pd.DataFrame(rows, columns=SENSOR_COLUMNS))


_DTYPES = {"name": "category", "sac": "int64", "sic": "int64"} | dict.fromkeys(RADAR_COLUMNS[3:], "float64") \
    | {"category": "int64", "kind": "object", "sigma_m": "float64"} \
    | dict.fromkeys(COVERAGE_COLUMNS, "float64")


def check_table(sensors: object) -> pd.DataFrame:
    """A sensor table given as a DataFrame (not through read_sensors) checked as a file's entries are:
    TypeError for another type; ValueError naming the row for a missing column or a site (latitude,
    longitude, altitude_m) that is not a finite number within its range."""
    if not isinstance(sensors, pd.DataFrame):
        raise TypeError(f"sensors: a {type(sensors).__name__}, not the sensor table; give "
                        "read_sensors(path)'s DataFrame or the TOML file's path")
    lacking = [c for c in REQUIRED_COLUMNS[1:] if c not in sensors]
    if lacking:
        raise ValueError(f"sensors: the table lacks {', '.join(lacking)} (read it with read_sensors)")
    for column in ("latitude", "longitude", "altitude_m"):
        values = pd.to_numeric(sensors[column], errors="coerce").to_numpy(float)
        low, high = _RANGES[column]
        with np.errstate(invalid="ignore"):
            bad = np.flatnonzero(~(np.isfinite(values) & (values >= low) & (values <= high)))
        if len(bad):
            i = int(bad[0])
            row = sensors.iloc[i]
            name = f"{row['name']!r}, " if "name" in sensors else ""
            raw = sensors[column].iloc[i]
            raw = raw.item() if hasattr(raw, "item") else raw
            raise ValueError(f"sensors: row {i} ({name}SAC {row['sac']} SIC {row['sic']}) {column} "
                             f"{raw!r}: expected a number within {low:g}..{high:g}")
    return sensors


def _typed(frame: pd.DataFrame) -> pd.DataFrame:
    return frame.astype(_DTYPES)


def no_sensors() -> pd.DataFrame:
    """An empty sensor table (SENSOR_COLUMNS, typed as read_sensors types them): no radar is placed."""
    return _typed(pd.DataFrame({c: [] for c in SENSOR_COLUMNS}))


def radar_entries(sensors: pd.DataFrame) -> pd.DataFrame:
    """The radar entries of a sensor table (RADAR_COLUMNS, as many as it has; every row of a table without a
    ``category`` column, as tables built by hand before reference points existed)."""
    if "category" not in sensors:
        return sensors
    radar = sensors["category"].to_numpy() == RADAR_CATEGORY
    return sensors if radar.all() else sensors[radar].reset_index(drop=True)


def reference_entries(sensors: pd.DataFrame | None) -> pd.DataFrame:
    """The multilateration and surface radar reference points of a sensor table (SENSOR_COLUMNS but the
    radar sigmas); an empty table when it has none."""
    if sensors is None or "category" not in sensors:
        return no_sensors().drop(columns=list(OPTIONAL_DEFAULTS))
    rows = sensors[sensors["category"].to_numpy() != RADAR_CATEGORY]
    return rows.drop(columns=list(OPTIONAL_DEFAULTS)).reset_index(drop=True)


def sensor_sites(reports: pd.DataFrame, sensors: pd.DataFrame) -> pd.DataFrame:
    """The sensor-table row (SENSOR_COLUMNS) of each report's SAC/SIC, aligned with ``reports`` by position;
    UnknownRadar for pairs the table lacks. Sigma columns missing from ``sensors`` take their defaults."""
    sensors = radar_entries(sensors)
    if sensors.duplicated(["sac", "sic"]).any():
        raise ValueError("sensor table lists a SAC/SIC pair twice")
    table = sensors.assign(**{k: sensors[k] if k in sensors else v for k, v in OPTIONAL_DEFAULTS.items()})
    table = table.astype({"name": "category", "sac": "Int64", "sic": "Int64"})[RADAR_COLUMNS]
    codes, declared = pair_codes(reports["sac"], reports["sic"]), pair_codes(table["sac"], table["sic"])
    order = np.argsort(declared, kind="stable")
    at = order[np.minimum(np.searchsorted(declared[order], codes), len(order) - 1)] if len(order) else None
    unknown = declared[at] != codes if at is not None else np.ones(len(codes), bool)
    if unknown.any():
        pairs = pd.DataFrame({c: reports[c].astype("Int64").to_numpy()[unknown] for c in ("sac", "sic")})
        pairs = pairs.drop_duplicates().sort_values(["sac", "sic"])
        raise UnknownRadar([(int(a) if pd.notna(a) else pd.NA, int(b) if pd.notna(b) else pd.NA)
                            for a, b in pairs.itertuples(index=False)])
    return table.iloc[at].reset_index(drop=True)


def undeclared_radars(reports: pd.DataFrame, sensors: pd.DataFrame) -> pd.DataFrame:
    """Per SAC/SIC pair (and file) of ``reports`` that ``sensors`` does not list: sac, sic, file, records and
    the first record's offset, in file order of first appearance; SAC/SIC missing shows as <NA>."""
    columns = ["sac", "sic", "file", "records", "offset"]
    sensors = radar_entries(sensors)
    declared = pair_codes(sensors["sac"], sensors["sic"])
    unknown = ~np.isin(pair_codes(reports["sac"], reports["sic"]), declared)
    if not unknown.any():
        return pd.DataFrame(columns=columns)
    reports = reports[unknown]
    keys = pd.DataFrame({"sac": reports["sac"].astype("Int64").to_numpy(),
                         "sic": reports["sic"].astype("Int64").to_numpy(),
                         "file": (reports["file"].astype("string").to_numpy() if "file" in reports
                                  else pd.array([pd.NA] * len(reports), dtype="string")),
                         "offset": (reports["offset"].astype("Int64").to_numpy() if "offset" in reports
                                    else pd.array([pd.NA] * len(reports), dtype="Int64"))})
    groups = keys.groupby(["sac", "sic", "file"], dropna=False, sort=False)
    return groups.agg(records=("offset", "size"), offset=("offset", "first")).reset_index()[columns]


def implausible_altitudes(sensors: pd.DataFrame, sensors_path) -> list[str]:
    """A warning per sensor whose altitude_m lies outside SITE_ALTITUDE_RANGE_M (``sensors_path``: the file
    the warnings name)."""
    odd = sensors[~sensors["altitude_m"].between(*SITE_ALTITUDE_RANGE_M)]
    lo, hi = SITE_ALTITUDE_RANGE_M
    return [f"--sensors {sensors_path}: {row.name!r} altitude_m = {row.altitude_m:g} is implausible for a "
            f"{'radar site' if getattr(row, 'kind', 'radar') == 'radar' else 'reference point'}"
            f" (expected {lo:g} to {hi:g} m)"
            for row in odd.itertuples()]


def stray_verdict(stray: pd.DataFrame, n_cat048: int, sensors_path: str | None) -> list[str]:
    """Judge the records of SAC/SIC pairs the sensor file lacks (undeclared_radars' table, over the run's
    n_cat048 CAT048 records): UnknownRadar for the pairs with enough records to be a radar, else one
    warning per pair and file, the records being left out."""
    limit = max(STRAY_RADAR_RECORDS, math.ceil(STRAY_RADAR_SHARE * n_cat048))
    per_pair = stray.groupby(["sac", "sic"], dropna=False, sort=False)["records"].transform("sum")
    no_pair = (stray["sac"].isna() | stray["sic"].isna()).to_numpy(bool)
    real = stray[~no_pair & (per_pair >= limit).to_numpy(bool)]
    if len(real):
        pairs = real[["sac", "sic"]].drop_duplicates().sort_values(["sac", "sic"])
        raise UnknownRadar([(int(a), int(b)) for a, b in pairs.itertuples(index=False)])
    warnings = []
    for row in stray.itertuples(index=False):
        name = row.file if pd.notna(row.file) else "input"
        if pd.isna(row.sac) or pd.isna(row.sic):
            why = "carry no SAC/SIC (I048/010), so no sensor entry can place them"
            pair = "without SAC/SIC"
        else:
            pair = f"from SAC/SIC {row.sac}/{row.sic}"
            where = sensors_path if sensors_path is not None else "a sensor file (no --sensors given)"
            why = (f"not in {where} and too few for a radar (fewer than {limit}: the larger of "
                   f"{STRAY_RADAR_RECORDS} and {STRAY_RADAR_SHARE:.1%} of the {n_cat048} CAT048 records), "
                   "taken for damaged data")
        warnings.append(f"{name}: {row.records} CAT048 record(s) {pair} (first at offset {row.offset}) "
                        f"{why}, left out of the measurements")
    return warnings


def declared_radar(cat048: pd.DataFrame | None, sensors: pd.DataFrame, sensors_path: str | None
                   ) -> tuple[pd.DataFrame | None, list[str]]:
    """The CAT048 records of radars the sensor file lists, and the warnings of stray_verdict: records of a
    SAC/SIC it lacks are left out when too few to be a radar or without SAC/SIC; UnknownRadar otherwise."""
    if cat048 is None or cat048.empty:
        return cat048, []
    stray = undeclared_radars(cat048, sensors)
    if stray.empty:
        return cat048, []
    warnings = stray_verdict(stray, len(cat048), sensors_path)
    keys = pd.MultiIndex.from_arrays([cat048["sac"].astype("Int64"), cat048["sic"].astype("Int64")])
    known = keys.isin(pd.MultiIndex.from_frame(radar_entries(sensors)[["sac", "sic"]].astype("Int64")))
    return cat048[known], warnings


class UnknownReferencePoint(ValueError):
    """CAT010/CAT020 reports to place from a reference point the sensor table lacks: (category, kind, SAC,
    SIC) each, with the entries to add."""

    def __init__(self, missing: list[tuple[int, str, int, int]]):
        self.missing = missing
        names = ", ".join(f"CAT{c:03d} {KIND_NOUN[k]} SAC {a} SIC {b}" for c, k, a, b in missing)
        snippets = "\n".join(reference_toml_snippet(*m) for m in missing)
        super().__init__(f"{names}: Cartesian positions from a reference point the sensor table does not "
                         f"give; add:\n{snippets}")


def reference_toml_snippet(category: int, kind: str, sac: int, sic: int) -> str:
    """The ``[[sensor]]`` lines for a multilateration or surface radar reference point the sensor file
    lacks (read_sensors refuses the 0 N 0 E placeholder until it is edited)."""
    default = DEFAULT_SIGMA_M.get(category)
    sigma = (f"# optional: sigma_m = 1-sigma error per axis of reports without I{category:03d}/500 "
             + (f"(default {default:.2f} m)\n" if default else "(none by default: no covariance)\n"))
    return (
        "[[sensor]]  # replace the three TODO values: msdc refuses a point at latitude 0, longitude 0\n"
        f'name = "{KIND_NOUN[kind]} SAC {sac} SIC {sic}"\n'
        f"category = {category}\n"
        f'kind = "{kind}"\n'
        f"sac = {sac}\n"
        f"sic = {sic}\n"
        "latitude = 0.0    # TODO: the system's reference point (origin of its x/y), degrees north\n"
        "longitude = 0.0   # TODO: degrees east (WGS-84)\n"
        "altitude_m = 0.0  # TODO: its height above the WGS-84 ellipsoid, metres\n"
        + sigma
    )


def sensor_toml_snippet(sac: int, sic: int) -> str:
    """The ``[[sensor]]`` lines to add to the sensor file for a radar that is not in it (read_sensors refuses
    their 0 N 0 E placeholder site until it is edited); for records missing their SAC or SIC, a comment saying
    that no entry can place them (``sac = <NA>`` is not TOML)."""
    if pd.isna(sac) or pd.isna(sic):
        return (f"# SAC {sac} SIC {sic}: records without a complete data source identifier (I048/010)\n"
                "# match no [[sensor]] entry; leave them out (msdc's commands do, with a warning)\n")
    return (
        "[[sensor]]  # replace the three TODO values: msdc refuses a site at latitude 0, longitude 0\n"
        f'name = "radar SAC {sac} SIC {sic}"\n'
        f"sac = {sac}\n"
        f"sic = {sic}\n"
        "latitude = 0.0    # TODO: antenna latitude, degrees north (WGS-84)\n"
        "longitude = 0.0   # TODO: antenna longitude, degrees east (WGS-84)\n"
        "altitude_m = 0.0  # TODO: antenna height above the WGS-84 ellipsoid, metres\n"
        "# optional: sigma_range_m = 70.0, sigma_azimuth_deg = 0.08 (1-sigma plot noise)\n"
    )
