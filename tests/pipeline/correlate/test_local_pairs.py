"""--pairs mlat-adsb and smr-mlat: multilateration correlated against ADS-B, surface radar against
multilateration, each pair's separation what the positions were made with (pyproj's geodesic)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from measurement_frames import meas_frame
from pyproj import Geod

from msdc.pipeline.correlate.correlation import NoSuchAircraft, correlate

GEOD = Geod(ellps="WGS84")
REF = (45.0, 5.0)


def rows(kind, sensor, t, east, north, **cols):
    east, north = np.broadcast_arrays(np.asarray(east, float), np.asarray(north, float))
    lon, lat, _ = GEOD.fwd(np.full(east.shape, REF[1]), np.full(east.shape, REF[0]),
                           np.degrees(np.arctan2(east, north)), np.hypot(east, north))
    return pd.DataFrame({"time_of_day": t, "latitude": lat, "longitude": lon, "sensor_kind": kind,
                         "sensor_id": sensor, "address": "4CA1B2", "ground_speed_kt": 20.0, **cols})


T = np.arange(0.0, 600.0, 1.0)
NORTH = 10.0 * T - 3000.0  # due north at 10 m/s
MEAS = meas_frame(pd.concat([
    rows("adsb", "021:0/107", T, 0.0, NORTH),
    rows("mlat", "010:0/107:mlat", T, 20.0, NORTH),  # 20 m east of ADS-B
    rows("smr", "010:0/7:smr", T, 20.0, NORTH + 15.0),  # 15 m north of the multilateration
    rows("radar", "048:0/1", T, -500.0, NORTH, sac=0, sic=1),  # a radar 500 m west of ADS-B
], ignore_index=True))


@pytest.mark.parametrize(("pairs", "tested", "reference", "sep_m"), [
    ("mlat-adsb", "010:0/107:mlat", "021:0/107", 20.0),
    ("smr-mlat", "010:0/7:smr", "010:0/107:mlat", 15.0),
    ("radar-adsb", "048:0/1", "021:0/107", 500.0),  # the other kinds stay out of the ADS-B reference
])
def test_each_pair_kind_against_its_reference(pairs, tested, reference, sep_m):
    run = correlate(MEAS, all_aircraft=True, pairs=pairs)
    (window,) = run.windows
    assert (window.summary["radar_sensor"], window.summary["reference_sensor"]) == (tested, reference)
    assert window.summary["sep_median_m"] == pytest.approx(sep_m, abs=0.05)
    assert run.parameters["pairs"] == pairs


def test_an_aircraft_not_seen_by_the_pair_is_named_in_its_terms():
    meas = MEAS[(MEAS["sensor_kind"] != "mlat").to_numpy()].reset_index(drop=True)
    with pytest.raises(NoSuchAircraft, match="multilateration"):
        correlate(meas, callsign=None, address="4CA1B2", pairs="mlat-adsb")
    with pytest.raises(NoSuchAircraft, match="surface radar and multilateration"):
        correlate(meas, all_aircraft=True, pairs="smr-mlat")
    # seen by multilateration alone: the closest name said "(radar only)" against ADS-B and "(ADS-B only)"
    # against a surface radar, the roles' words
    alone = MEAS[(MEAS["sensor_kind"] == "mlat").to_numpy()].reset_index(drop=True)
    for pairs, missing in (("mlat-adsb", "ADS-B"), ("smr-mlat", "surface radar")):
        with pytest.raises(NoSuchAircraft) as caught:
            correlate(alone, address="4CA1B2", pairs=pairs)
        assert str(caught.value) == (f"address 4CA1B2 not seen by {missing}; closest present: 4CA1B2 "
                                     "(multilateration only)")


@pytest.mark.parametrize(("pairs", "named", "phrase"), [
    ("smr-mlat", "010:0/7:smr", "from 010:0/107:mlat"),
    ("mlat-adsb", "010:0/107:mlat", "from ADS-B"),
])
def test_a_verdict_names_the_reference_it_was_measured_against(pairs, named, phrase):
    """The surface radar's verdict against multilateration said "RMS from ADS-B" (its reference takes the
    ADS-B role's columns, not its name), and what each window shows began "every radar report"."""
    from msdc.pipeline.report.summary import lead_json

    run = correlate(MEAS, all_aircraft=True, pairs=pairs)
    (window,) = run.windows
    verdict = window.summary["verdict"]
    assert window.summary["radar_sensor"] == named
    assert f"m RMS {phrase} over" in verdict
    about = lead_json(run)["about"]
    noun = {"smr-mlat": "surface radar", "mlat-adsb": "multilateration"}[pairs]
    assert about.startswith(f"What each window shows: every {noun} report against the reference's position")
    if pairs == "smr-mlat":
        assert "ADS-B" not in verdict and "ADS-B" not in about


def test_the_slot_charts_name_a_surface_radar_and_its_multilateration(tmp_path):
    """The workbook's slot charts called the two sides "Radar" and "ADS-B" whatever --pairs was."""
    from openpyxl import Workbook, load_workbook

    from msdc.pipeline.report.charts import write_slot_charts

    wb = Workbook(write_only=True)
    write_slot_charts(wb, correlate(MEAS, all_aircraft=True, pairs="smr-mlat"))
    wb.save(tmp_path / "c.xlsx")
    ws = load_workbook(tmp_path / "c.xlsx")["Slot charts"]
    names = [[s.tx.v for s in chart.series] for chart in ws._charts]
    assert names == [["Surface radar", "Multilateration"]] * 2  # latitude, longitude
    assert ws["A2"].value.startswith("Multilateration yellow (solid, wide), surface radar red (dashed")


@pytest.mark.parametrize(("pairs", "title"), [
    ("smr-mlat", "Slotted tracks: surface radar (red) and multilateration (yellow), every correlated window"),
    ("radar-adsb", "Slotted tracks: radar (red) and ADS-B (yellow), every correlated window"),
])
def test_the_map_sheet_names_the_pair_it_draws(tmp_path, pairs, title):
    """The Map sheet's title said "radar (red) and ADS-B (yellow)" whatever --pairs was."""
    from matplotlib import pyplot as plt
    from openpyxl import load_workbook

    from msdc.pipeline.report.excel import write_report

    png = tmp_path / "map.png"
    plt.imsave(png, np.zeros((4, 4)))
    write_report(correlate(MEAS, all_aircraft=True, pairs=pairs), tmp_path / "r.xlsx", figure_png=png)
    assert load_workbook(tmp_path / "r.xlsx", read_only=True)["Map"]["A1"].value == title


def test_jumps_are_not_counted_where_the_reference_is_not_adsb(tmp_path):
    """A surface radar's multilateration reference is not searched for ADS-B position jumps: its windows
    said "0 jumps", a count of what was never looked for; ADS-B's jumps are still counted (one here)."""
    import json

    from msdc.pipeline.report.excel import write_report
    from msdc.pipeline.report.summary import run_to_json, summary_table

    jumped = MEAS.copy()
    at = np.flatnonzero((jumped["sensor_kind"] == "adsb").to_numpy() & (jumped["time_of_day"] == 300.0))
    jumped.loc[at, "latitude"] += 0.05  # 5.6 km north for one report: an ADS-B position jump
    (adsb_window,) = correlate(jumped, all_aircraft=True, pairs="mlat-adsb").windows
    assert adsb_window.summary["adsb_jumps"] == 1
    run = correlate(jumped, all_aircraft=True, pairs="smr-mlat")
    assert run.windows[0].summary["adsb_jumps"] is None
    doc = json.loads(json.dumps(run_to_json(run)))
    assert doc["windows"][0]["adsb_jumps"] is None
    table = summary_table(run).splitlines()
    header = next(line for line in table if line.startswith("call sign") and "jumps" in line)
    row = table[table.index(header) + 2]
    assert row[header.index("jumps"):].split()[0] == "-"
    write_report(run, tmp_path / "r.xlsx")  # a window with no jump count is written, not refused


def test_slot_chart_axes_tell_a_taxiing_aircrafts_ticks_apart(tmp_path):
    """A surface window's latitude axis printed 0.00 deg ticks (1.1 km): two ticks read 41.30. 300 m of
    taxiing north is 0.0027 deg, five ticks 0.00054 deg apart: four decimals tell them apart; the 6 km of
    the module's track (0.054 deg, ticks 0.011 apart) keep two."""
    from openpyxl import Workbook, load_workbook

    from msdc.pipeline.report.charts import write_slot_charts

    taxi = 0.5 * T - 150.0  # north at 0.5 m/s: 300 m in 600 s
    meas = meas_frame(pd.concat([rows("mlat", "010:0/107:mlat", T, 20.0, taxi),
                                 rows("smr", "010:0/7:smr", T, 20.0, taxi + 15.0)], ignore_index=True))
    formats = {}
    for name, frame in (("taxi", meas), ("module", MEAS)):
        wb = Workbook(write_only=True)
        write_slot_charts(wb, correlate(frame, all_aircraft=True, pairs="smr-mlat"))
        wb.save(tmp_path / f"{name}.xlsx")
        (lat_chart, _) = load_workbook(tmp_path / f"{name}.xlsx")["Slot charts"]._charts
        formats[name] = lat_chart.y_axis.number_format.formatCode
    assert formats == {"taxi": "0.0000", "module": "0.00"}


def test_a_frame_without_a_needed_column_or_with_infinite_positions_is_refused():
    """A frame without latitude (or call sign, or sensor kind) raised pandas' bare KeyError; infinite
    latitudes ran on, with numpy's warnings, and the separations came out None with nothing said."""
    for column in ("latitude", "callsign", "sensor_kind"):
        with pytest.raises(ValueError, match=rf"^meas: lacks the column\(s\) {column} \(a measurement frame"):
            correlate(MEAS.drop(columns=column), all_aircraft=True, pairs="mlat-adsb")
    bad = MEAS.copy()
    bad.loc[bad.index[[5, 9]], "latitude"] = np.inf
    with pytest.raises(ValueError, match=rf"^meas: 2 row\(s\) with an infinite latitude, the first at index "
                                         rf"{bad.index[5]}: a position is finite, or NaN where unknown"):
        correlate(bad, all_aircraft=True, pairs="mlat-adsb")


def test_an_address_given_as_a_number_is_a_type_error():
    """address=0x750312 is the int 7668498: it was looked for as "7668498" ("not seen")."""
    with pytest.raises(TypeError, match=r"^address 7668498: a string \(an address as 6 hex digits"):
        correlate(MEAS, address=0x750312)
    with pytest.raises(TypeError, match=r"^callsign 72: a string"):
        correlate(MEAS, callsign=72)
