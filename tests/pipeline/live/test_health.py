"""The live monitor's figures on tiny hand-built windows: every expected value is worked out by hand here
(the 95 % intervals by scipy's beta quantiles, the Clopper-Pearson formula, not msdc's own code)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from scipy.stats import beta

from msdc.pipeline.live.health import (
    judged,
    live_pd,
    live_validity,
    lookback_s,
    snapshot,
    targets,
    update_interval_s,
)
from msdc.pipeline.live.monitor import Thresholds

T0 = pd.Timestamp("2026-11-28T12:00:00Z")
NOW = 1_800_000_000.0  # the wall clock of the tests (s since 1970)


def reports(sensor: str, track: int, scans: list[int], period_s: float = 4.0, wall0: float = NOW - 60.0,
            **columns) -> pd.DataFrame:
    """One track's reports at the given scan numbers: its report times every period_s from T0, its arrival
    (wall_s) as many seconds after wall0, moving north 0.01 deg per scan; extra columns as given."""
    k = np.asarray(scans, float)
    n = len(scans)
    frame = pd.DataFrame({
        "time": T0 + pd.to_timedelta(k * period_s, unit="s"), "sensor_id": sensor,
        "sensor_kind": "radar" if sensor.startswith("048") else "adsb",
        "latitude": 2.7 + 0.01 * k, "longitude": 101.7 + 0.1 * track, "track_number": pd.array([track] * n,
                                                                                             "Int16"),
        "aircraft_id": f"AC{track}", "callsign": f"MAS{track}", "mode3a": "1234", "flight_level": 100.0 + k,
        "wall_s": wall0 + k * period_s, "feed": "udp:239.1.2.3:8600"})
    for name, values in columns.items():
        frame[name] = values
    return frame


def two_tracks_with_misses() -> pd.DataFrame:
    """Two tracks seen over scans 0..9 of a 4 s radar, each missing scans 3 and 6: 16 of 20 updates."""
    seen = [0, 1, 2, 4, 5, 7, 8, 9]
    return pd.concat([reports("048:25/201", 101, seen), reports("048:25/201", 102, seen)], ignore_index=True)


def clopper_pearson(k: int, n: int) -> tuple[float, float]:
    return float(beta.ppf(0.025, k, n - k + 1)), float(beta.ppf(0.975, k + 1, n - k))


def test_pd_of_two_tracks_missing_two_scans_each_is_16_of_20() -> None:
    window = two_tracks_with_misses()
    assert update_interval_s(window) == pytest.approx(4.0)  # (9 scans x 4 s) x 2 / 18 scans
    out = live_pd(window, "048:25/201", 120.0)
    assert (out.count, out.n) == (16, 20)
    assert out.value == pytest.approx(0.8)
    lo, hi = clopper_pearson(16, 20)
    assert (out.ci_low, out.ci_high) == (pytest.approx(lo), pytest.approx(hi))
    assert hi == pytest.approx(0.9427, abs=1e-4)


def test_a_radar_heard_without_sensors_still_has_its_interval_and_codes() -> None:
    """listen without --sensors: radar plots have no position. Their update interval and codes' validity
    need none, yet were withheld with false reasons ("fewer than 10 intervals", "no report states whether
    its mode3a is validated"); the PD, which places the reports, now says why it is withheld."""
    window = two_tracks_with_misses().assign(latitude=np.nan, longitude=np.nan,
                                             mode3a_valid=pd.array([True] * 15 + [False], "boolean"))
    assert update_interval_s(window) == pytest.approx(4.0)  # (9 scans x 4 s) x 2 / 18 scans, as placed
    out = live_validity(window, "mode3a_valid")
    assert (out.count, out.n) == (15, 16)
    pd_out = live_pd(window, "048:25/201", 120.0)
    assert np.isnan(pd_out.value) and "the reports carry no position" in pd_out.notes[0]
    assert "give --sensors" in pd_out.notes[0]


def test_pd_is_degraded_only_when_its_whole_interval_is_below_the_threshold() -> None:
    out = live_pd(two_tracks_with_misses(), "048:25/201", 120.0)  # 0.8, interval up to 0.943
    assert judged(out, 0.97)["state"] == "degraded"
    assert judged(out, 0.90)["state"] == "low"  # below 0.9, but 16/20 cannot show it yet
    assert judged(out, 0.80)["state"] == "ok"


def test_pd_is_withheld_when_the_update_period_cannot_be_measured() -> None:
    window = reports("048:25/201", 7, [0, 1, 2, 3, 4, 5])  # 5 intervals: fewer than 10
    out = live_pd(window, "048:25/201", 120.0)
    figure = judged(out, 0.97)
    assert figure["value"] is None and figure["state"] == "withheld"
    assert "update period not measurable" in figure["note"]
    assert np.isnan(update_interval_s(window))


def test_plots_without_track_or_identity_are_left_out_of_pd() -> None:
    window = two_tracks_with_misses()
    stray = reports("048:25/201", 9, [3, 6])
    stray["track_number"] = pd.array([pd.NA, pd.NA], "Int16")
    stray["aircraft_id"] = None
    out = live_pd(pd.concat([window, stray], ignore_index=True), "048:25/201", 120.0)
    assert (out.count, out.n) == (16, 20)  # they do not fill the two tracks' misses


def test_mode3a_validity_counts_only_reports_that_state_it() -> None:
    valid = [True] * 15 + [False] * 3 + [pd.NA] * 2
    window = reports("048:25/201", 5, list(range(20)), mode3a_valid=pd.array(valid, "boolean"))
    out = live_validity(window, "mode3a_valid")
    assert (out.count, out.n) == (15, 18)
    lo, hi = clopper_pearson(15, 18)
    assert (out.ci_low, out.ci_high) == (pytest.approx(lo), pytest.approx(hi))


def test_validity_is_withheld_on_a_small_sample_or_when_the_feed_does_not_say() -> None:
    few = reports("048:25/201", 5, list(range(9)), modec_valid=pd.array([True] * 9, "boolean"))
    out = judged(live_validity(few, "modec_valid"), 0.96)
    assert out["value"] is None and "9 reports carry a flight_level" in out["note"]
    silent = reports("048:25/201", 5, list(range(20)), modec_valid=pd.array([pd.NA] * 20, "boolean"))
    assert "no report in the window states" in live_validity(silent, "modec_valid").notes[0]
    bare = reports("048:25/201", 5, list(range(20)))
    assert "do not say whether" in live_validity(bare, "mode3a_valid").notes[0]


def _counters(records: dict[str, int], **feed) -> dict:
    return {"udp:239.1.2.3:8600": {"packets": 100, "bytes": 10_000, "unframed": 0, "decode_errors": 0,
                                   "dropped": 0, "records": records, "last_packet_wall_s": NOW - 1.0, **feed}}


def _sensor(snap: dict, sensor_id: str) -> dict:
    return next(s for s in snap["sensors"] if s["sensor_id"] == sensor_id)


def test_a_sensor_last_heard_31_s_ago_is_silent_with_a_30_s_threshold() -> None:
    th = Thresholds(silent_s=30.0)
    old = reports("048:25/201", 1, [0], wall0=NOW - 31.0)
    fresh = reports("021:0/1", 2, [0], wall0=NOW - 29.0)
    snap, _ = snapshot(pd.concat([old, fresh], ignore_index=True), _counters({"048:25/201": 1, "021:0/1": 1}),
                       {}, NOW, NOW - 300.0, th)
    assert [(a["kind"], a["sensor_id"]) for a in snap["alarms"]] == [("silent", "048:25/201")]
    assert _sensor(snap, "048:25/201")["last_report_age_s"] == pytest.approx(31.0)
    assert _sensor(snap, "021:0/1")["alarms"] == []


def test_status_messages_make_no_sensor_panel() -> None:
    """A radar's CAT034 messages counted as records of "034:25/201" give its panel a status age, not a
    panel of their own (which would be silent forever)."""
    th = Thresholds(silent_s=30.0)
    snap, _ = snapshot(reports("048:25/201", 1, [0], wall0=NOW - 1.0),
                       _counters({"048:25/201": 1, "034:25/201": 40}),
                       {"048:25/201": NOW - 3.0, "034:25/201": NOW - 3.0}, NOW, NOW - 300.0, th)
    assert [s["sensor_id"] for s in snap["sensors"]] == ["048:25/201"] and snap["alarms"] == []
    assert snap["sensors"][0]["last_status_age_s"] == pytest.approx(3.0)


def test_a_sensor_gone_from_the_window_is_silent_and_remembered() -> None:
    th = Thresholds(silent_s=10.0, window_s=20.0)
    assert lookback_s(th) == 20.0
    first, memory = snapshot(reports("048:25/201", 1, [0], wall0=NOW - 5.0), _counters({"048:25/201": 1}), {},
                             NOW, NOW - 100.0, th)
    assert first["alarms"] == []
    later, _ = snapshot(reports("048:25/201", 1, [])[:0], _counters({"048:25/201": 1}), {}, NOW + 60.0,
                        NOW - 100.0, th, memory)
    assert _sensor(later, "048:25/201")["last_report_age_s"] == pytest.approx(65.0)
    assert [a["kind"] for a in later["alarms"]] == ["silent"]
    # never in a window the monitor saw, only in the counters: silent for longer than the lookback
    unseen, _ = snapshot(reports("048:25/201", 1, [])[:0], _counters({"048:25/201": 1}), {}, NOW, NOW - 1e3,
                         th)
    assert _sensor(unseen, "048:25/201")["last_report_age_s"] is None
    # a state with nothing at all in the window (not even columns) gives the same
    bare, _ = snapshot(pd.DataFrame(), _counters({"048:25/201": 1}), {}, NOW, NOW - 1e3, th)
    assert bare["alarms"] == unseen["alarms"] and bare["targets"] == [] and bare["centre"] is None
    assert _sensor(bare, "048:25/201")["pd"]["note"] == "no report in the window"
    assert "no report in the last 20 s" in unseen["alarms"][0]["message"]


def test_report_rate_status_age_and_degraded_alarm() -> None:
    th = Thresholds(window_s=120.0, min_pd=0.97)
    window = two_tracks_with_misses()  # 16 reports, the last one 60 - 36 = 24 s ago
    snap, _ = snapshot(window, _counters({"048:25/201": 500}), {"048:25/201": NOW - 2.5}, NOW, NOW - 300.0,
                       th)
    s = _sensor(snap, "048:25/201")
    assert s["reports_per_s"] == pytest.approx(16 / 120.0)
    assert s["reports_in_window"] == 16 and s["records_total"] == 500
    assert s["last_status_age_s"] == pytest.approx(2.5)
    assert s["last_report_age_s"] == pytest.approx(24.0)
    assert s["pd"]["value"] == pytest.approx(0.8) and s["alarms"] == ["degraded_pd"]
    assert s["mode3a_valid"]["value"] is None  # the frame does not say
    # 60 s after the start the rate is over those 60 s
    young, _ = snapshot(window, _counters({"048:25/201": 16}), {}, NOW, NOW - 60.0, th)
    assert _sensor(young, "048:25/201")["reports_per_s"] == pytest.approx(16 / 60.0)
    json.dumps(snap, allow_nan=False)  # plain JSON: no NaN anywhere


def test_every_rate_says_the_window_it_was_measured_over() -> None:
    """A rate over less than its nominal window was unlabelled. 16 reports 45 s after the start of a 120 s
    window: 16 / 45 per second over 45 s; 300 s after it, 16 / 120 over 120 s. A feed counted at snapshots
    20 s and 10 s ago, in a 15 s window: the 30 packets since the one 10 s ago, over 10 s."""
    th = Thresholds(window_s=120.0)
    young, _ = snapshot(two_tracks_with_misses(), _counters({"048:25/201": 16}), {}, NOW, NOW - 45.0, th)
    radar = _sensor(young, "048:25/201")
    assert (radar["reports_per_s"], radar["rate_window_s"]) == (pytest.approx(16 / 45.0), 45.0)
    old, _ = snapshot(two_tracks_with_misses(), _counters({"048:25/201": 16}), {}, NOW, NOW - 300.0, th)
    radar = _sensor(old, "048:25/201")
    assert (radar["reports_per_s"], radar["rate_window_s"]) == (pytest.approx(16 / 120.0), 120.0)
    short = Thresholds(window_s=15.0)
    _, memory = snapshot(pd.DataFrame(), _counters({}, packets=10), {}, NOW - 20.0, NOW - 21.0, short)
    _, memory = snapshot(pd.DataFrame(), _counters({}, packets=70), {}, NOW - 10.0, NOW - 21.0, short, memory)
    snap, _ = snapshot(pd.DataFrame(), _counters({}, packets=100), {}, NOW, NOW - 21.0, short, memory)
    feed = snap["feeds"][0]
    assert (feed["packets_per_s"], feed["rate_window_s"]) == (pytest.approx(3.0), 10.0)


def test_feed_rates_and_decode_errors_over_the_window() -> None:
    th = Thresholds(window_s=30.0)
    empty = reports("048:25/201", 1, [])[:0]
    _, memory = snapshot(empty, _counters({}, packets=100), {}, NOW - 40.0, NOW - 100.0, th)
    _, memory = snapshot(empty, _counters({}, packets=200), {}, NOW - 20.0, NOW - 100.0, th, memory)
    snap, _ = snapshot(empty, _counters({}, packets=260, decode_errors=3), {}, NOW, NOW - 100.0, th, memory)
    feed = snap["feeds"][0]
    assert feed["packets_per_s"] == pytest.approx(60 / 20.0)  # the sample 40 s ago is outside the window
    assert feed["decode_errors_in_window"] == 3 and feed["last_packet_age_s"] == pytest.approx(1.0)
    assert [(a["level"], a["kind"]) for a in snap["alarms"]] == [("warning", "decode_errors")]


def test_a_window_as_short_as_the_snapshots_still_counts_the_feed() -> None:
    """--window 1 with snapshots a second apart: the snapshot before is just outside the window, so no
    counter was remembered inside it, and packets per second and the unframed warning were silent. The
    change since that snapshot is what came within the window: 7 unframed over 1.02 s."""
    th = Thresholds(window_s=1.0)
    _, memory = snapshot(pd.DataFrame(), _counters({}, packets=50, unframed=2), {}, NOW - 2.04, NOW - 9.0, th)
    _, memory = snapshot(pd.DataFrame(), _counters({}, packets=60, unframed=4), {}, NOW - 1.02, NOW - 9.0, th,
                         memory)
    snap, _ = snapshot(pd.DataFrame(), _counters({}, packets=90, unframed=11), {}, NOW, NOW - 9.0, th, memory)
    feed = snap["feeds"][0]
    assert (feed["packets_per_s"], feed["rate_window_s"]) == (pytest.approx(30 / 1.02), 1.02)
    assert feed["unframed_in_window"] == 7
    assert [a["kind"] for a in snap["alarms"]] == ["unframed"]


def test_a_feeds_packets_are_framed_unframed_empty_dropped_or_waiting() -> None:
    """100 packets: 90 framed, 3 unframed, 2 empty, 1 dropped, so 4 still waiting to be decoded."""
    snap, _ = snapshot(pd.DataFrame(), _counters({}, framed=90, unframed=3, empty=2, dropped=1), {}, NOW,
                       NOW - 100.0, Thresholds())
    feed = snap["feeds"][0]
    assert {k: feed[k] for k in ("packets", "framed", "unframed", "empty", "dropped", "waiting")} == {
        "packets": 100, "framed": 90, "unframed": 3, "empty": 2, "dropped": 1, "waiting": 4}


def test_targets_trails_labels_and_staleness() -> None:
    window = pd.concat([reports("048:25/201", 101, [0, 1, 2], wall0=NOW - 8.0),
                        reports("048:25/201", 102, [0], wall0=NOW - 20.0)], ignore_index=True)
    window.loc[2, "callsign"] = None  # the latest report of 101 without a call sign: the last known is kept
    window["aircraft_id"] = None  # followed by their track numbers
    shown = targets(window, NOW)
    assert [t["id"] for t in shown] == ["048:25/201|T101", "048:25/201|T102"]  # most recent first
    first = shown[0]
    assert first["trail"] == [[2.7, 101.7 + 10.1], [2.71, 101.7 + 10.1], [2.72, 101.7 + 10.1]]
    assert (first["callsign"], first["mode3a"], first["flight_level"]) == ("MAS101", "1234", 102.0)
    assert first["age_s"] == pytest.approx(0.0) and not first["stale"]
    # the arrival period is not measurable on 3 reports: stale after 15 s
    assert shown[1]["age_s"] == pytest.approx(20.0) and shown[1]["stale"]
    # one track of 12 arrivals 4 s apart: stale once over 3 x 4 s
    long = reports("048:25/201", 7, list(range(12)), wall0=NOW - 44.0 - 12.5)
    assert targets(long, NOW)[0]["stale"] and not targets(long, NOW - 1.0)[0]["stale"]
    assert targets(long, NOW)[0]["id"] == "048:25/201|A:AC7"  # the aircraft identity first


@pytest.mark.parametrize("field, value", [("min_pd", 1.5), ("silent_s", 0.0), ("window_s", float("nan"))])
def test_thresholds_refuse_values_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        Thresholds(**{field: value})


def test_a_large_window_is_measured_on_whole_tracks_in_a_fixed_order(monkeypatch) -> None:
    """12 tracks of 10 scans (odd ones 10 reports, even ones 8: 108) with MAX_FIGURE_REPORTS 45: the figures
    are measured on whole tracks in the order of their keys' CRC-32, each that still fits (after one that
    does not, a smaller one may), and the panel says so. PD is that of the tracks taken, shown without a
    verdict: the interval of a sample of whole tracks is too narrow to raise an alarm."""
    import zlib

    from msdc.pipeline.live import health

    monkeypatch.setattr(health, "MAX_FIGURE_REPORTS", 45)
    seen = [0, 1, 2, 4, 5, 7, 8, 9]
    frames = [reports("048:25/201", t, seen + ([3, 6] if t % 2 else [])) for t in range(1, 13)]
    window = pd.concat(frames, ignore_index=True)  # odd tracks complete (10 reports), even ones 8
    sizes = {f"A:AC{t}": 10 if t % 2 else 8 for t in range(1, 13)}
    order = sorted(sizes, key=lambda k: zlib.crc32(k.encode()))
    total, chosen = 0, []
    for k in order:  # whole tracks in CRC-32 order, each that still fits
        if total + sizes[k] <= 45:
            total, chosen = total + sizes[k], [*chosen, k]
    sample, said = health.figure_sample(window)
    assert said == {"tracks": len(chosen), "of_tracks": 12, "reports": total, "of_reports": len(window)}
    assert set("A:" + sample["aircraft_id"].astype(str)) == set(chosen)
    counters = {"udp:239.1.2.3:8600": {"records": {"048:25/201": len(window)}, "decode_errors": 0}}
    snap, _ = snapshot(window, counters, {}, NOW, NOW - 120.0, Thresholds(window_s=120.0))
    (panel,) = snap["sensors"]
    assert panel["figures_sample"] == said and panel["reports_in_window"] == len(window)
    updates = sum(10 for k in chosen)
    detected = sum(sizes[k] for k in chosen)
    assert (panel["pd"]["value"]) == pytest.approx(detected / updates)
    assert panel["pd"]["state"] == "unjudged"
    assert f"measured on {len(chosen)} of 12 tracks" in panel["pd"]["note"]
    assert health.figure_sample(window.iloc[:40])[1] is None  # up to the cap: every report


def test_a_large_window_without_tracks_is_measured_whole(monkeypatch) -> None:
    """ADS-B 0.23 carries no track numbers, nor do these reports an address: over the cap, the window was
    sampled by track with none to take, and every snapshot failed (IndexError) while the page showed its
    last figures as live; under it, the map's targets failed alike (no report to draw). It is measured
    whole: PD withheld (no track), no target, the snapshot made."""
    from msdc.pipeline.live import health

    monkeypatch.setattr(health, "MAX_FIGURE_REPORTS", 45)
    window = pd.concat([reports("021:0/107", t, range(10)) for t in range(1, 7)], ignore_index=True)
    window["aircraft_id"] = None
    window["track_number"] = pd.array([pd.NA] * len(window), dtype="Int64")
    sample, said = health.figure_sample(window)
    assert said is None and len(sample) == len(window) == 60
    counters = {"udp:239.1.2.3:8600": {"records": {"021:0/107": len(window)}, "decode_errors": 0}}
    snap, _ = snapshot(window, counters, {}, NOW, NOW - 120.0, Thresholds(window_s=120.0))
    (panel,) = snap["sensors"]
    assert panel["reports_in_window"] == 60 and panel["pd"]["state"] == "withheld"
    assert snap["targets"] == []


def test_a_sensor_whose_figures_fail_keeps_its_panel_and_the_others_theirs(monkeypatch) -> None:
    """One sensor's figures raising (as a window without tracks over the sample's cap once did) ended the
    whole snapshot: the page froze and no sensor's silence was judged. Now that sensor's panel shows its
    reports and silence with its figures withheld and a warning naming the failure; the other sensor's
    figures are measured as before (16 of 20 updates)."""
    from msdc.pipeline.live import health

    real = health.live_pd

    def failing(rows, sensor_id, window_s):  # on this sensor's data: none gives nothing to fail on
        if sensor_id == "021:0/1" and len(rows):
            raise ValueError("broken on purpose")
        return real(rows, sensor_id, window_s)

    monkeypatch.setattr(health, "live_pd", failing)
    th = Thresholds(silent_s=30.0)
    frame = pd.concat([two_tracks_with_misses(), reports("021:0/1", 5, [0], wall0=NOW - 31.0)],
                      ignore_index=True)
    snap, _ = snapshot(frame, _counters({"048:25/201": 16, "021:0/1": 1}), {}, NOW, NOW - 300.0, th)
    bad, good = _sensor(snap, "021:0/1"), _sensor(snap, "048:25/201")
    assert bad["pd"]["value"] is None and bad["pd"]["note"] == ("figures not computed: ValueError: broken on "
                                                                "purpose")
    assert bad["reports_in_window"] == 1 and set(bad["alarms"]) == {"silent", "figures_failed"}
    assert (good["pd"]["count"], good["pd"]["n"]) == (16, 20)
    alone, _ = snapshot(two_tracks_with_misses(), _counters({"048:25/201": 16}), {}, NOW, NOW - 300.0, th)
    assert good == _sensor(alone, "048:25/201")  # as if the failing sensor were not there
    assert [(a["kind"], a["sensor_id"]) for a in snap["alarms"] if a["sensor_id"] == "021:0/1"] == [
        ("silent", "021:0/1"), ("figures_failed", "021:0/1")]


def test_a_silent_sensor_keeps_its_kind() -> None:
    """A sensor gone from the lookback lost its kind: its panel read "048:25/201" with no "(radar)". Heard
    only in the counters now, each keeps the kind its category (and CAT010 its id's suffix) gives its
    reports: CAT048 radar, CAT021 ADS-B, CAT020 and CAT010 TYP 1 multilateration, CAT010 TYP 3 surface
    radar; CAT062 system tracks make no reports and have none."""
    th = Thresholds(silent_s=10.0, window_s=20.0)
    first, memory = snapshot(reports("048:25/201", 1, [0], wall0=NOW - 5.0), _counters({"048:25/201": 1}), {},
                             NOW, NOW - 100.0, th)
    assert _sensor(first, "048:25/201")["kind"] == "radar"
    kinds = {"048:25/201": "radar", "021:0/1": "adsb", "020:25/10": "mlat", "010:0/7:smr": "smr",
             "010:0/107:mlat": "mlat", "062:25/1": None}
    later, _ = snapshot(pd.DataFrame(), _counters(dict.fromkeys(kinds, 1)), {}, NOW + 60.0, NOW - 100.0, th,
                        memory)
    assert {s["sensor_id"]: s["kind"] for s in later["sensors"]} == kinds
    assert {a["sensor_id"] for a in later["alarms"]} == set(kinds)  # every one of them silent
