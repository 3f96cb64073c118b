"""ADS-B report filters: removed counts equal the simulator's injected jumps and low-NIC/NACp reports."""

from __future__ import annotations

import pandas as pd
import pytest
from frames import assert_frame_equal

from fixtures.simulate import simulate
from msdc.pipeline.model.measurements import adsb_measurements
from msdc.pipeline.quality.filters import FILTER_KEYS, apply_filters, filter_warnings

# one worker runs the module: the simulation made once, not on each worker
pytestmark = pytest.mark.xdist_group("filters")


@pytest.fixture(scope="module")
def sim():
    return simulate(seed=2019)


@pytest.fixture(scope="module")
def adsb(sim):
    return adsb_measurements(sim.adsb)


@pytest.fixture(scope="module")
def truth(sim):
    return sim.truth_tracks.query("sensor == 'adsb'").set_index("row").sort_index()


def test_off_by_default(adsb):
    kept, removed = apply_filters(adsb)
    assert list(removed) == FILTER_KEYS and not any(removed.values())
    assert_frame_equal(kept, adsb.reset_index(drop=True))


def test_low_nic_and_low_nacp_counts_equal_the_injected_episodes(sim, adsb, truth):
    injected = sum(sim.truth["low_quality"]["rows_by_aircraft"].values())
    assert injected == int(truth["low_quality"].sum()) > 0
    kept, removed = apply_filters(adsb, min_nic=6)
    assert removed["nic_below_min"] == injected
    assert len(kept) == len(adsb) - injected
    assert (kept["nucp_nic"] >= 6).all()
    _, removed = apply_filters(adsb, min_nacp=7)  # episodes are NACp 6, aircraft 8-9
    assert removed["nacp_below_min"] == injected and removed["nic_below_min"] == 0


def test_jumps_first_then_nic_then_nacp(sim, adsb, truth):
    jumps = truth["jump"].to_numpy()
    low = truth["low_quality"].to_numpy()
    kept, removed = apply_filters(adsb, drop_jumps=True, min_nic=6, min_nacp=7)
    assert removed["jumps"] == len(sim.truth["jumps"]) == int(jumps.sum())
    assert removed["nic_below_min"] == int((low & ~jumps).sum())  # a low-NIC jump counts as a jump
    assert removed["nacp_below_min"] == 0  # the same reports: already gone
    assert len(kept) == int((~jumps & ~low).sum())
    assert list(removed) == FILTER_KEYS


def test_missing_nic_and_nacp_are_kept_and_counted(adsb):
    a = adsb.copy()
    # row: (NIC, NACp) -> 3: (NA, 2) NACp filter; 5: (NA, NA) kept; 7: (NA, 9) kept;
    # 11: (2, NA) NIC filter (never reaches NACp); 20: (2, 2) NIC filter
    for row, nic, nacp in ((3, pd.NA, 2), (5, pd.NA, pd.NA), (7, pd.NA, 9), (11, 2, pd.NA), (20, 2, 2)):
        a.loc[row, ["nucp_nic", "nacp"]] = [nic, nacp]
    base_nic = int((adsb["nucp_nic"] < 6).sum())
    base_nacp = int(((adsb["nacp"] < 7) & (adsb["nucp_nic"] >= 6)).sum())
    kept, removed = apply_filters(a, min_nic=6, min_nacp=7)
    assert removed["nic_missing_kept"] == 3  # rows 3, 5, 7
    assert removed["nacp_missing_kept"] == 1  # row 5 (row 11 was removed by the NIC filter first)
    assert removed["nic_below_min"] == base_nic + 2
    assert removed["nacp_below_min"] == base_nacp + 1
    assert len(kept) == len(a) - base_nic - base_nacp - 3
    kept_keys = set(zip(kept["time"], kept["latitude"], strict=True))
    assert all((a.loc[r, "time"], a.loc[r, "latitude"]) in kept_keys for r in (5, 7))
    _, removed = apply_filters(a)  # no minimum set: nothing counted
    assert removed["nic_missing_kept"] == removed["nacp_missing_kept"] == 0


def test_empty_and_missing_columns(adsb):
    kept, removed = apply_filters(adsb.iloc[:0], drop_jumps=True, min_nic=6, min_nacp=7)
    assert kept.empty and not any(removed.values())
    # radar rows pass untouched, in place
    radar = adsb.iloc[:3].assign(sensor_kind="radar", nucp_nic=pd.NA)
    kept, removed = apply_filters(pd.concat([radar, adsb], ignore_index=True), min_nic=6)
    assert (kept["sensor_kind"].iloc[:3] == "radar").all()
    assert removed["nic_below_min"] == int((adsb["nucp_nic"] < 6).sum())
    no_nacp = adsb.drop(columns="nacp")
    kept, removed = apply_filters(no_nacp, min_nacp=7)
    assert len(kept) == len(adsb) and removed["nacp_missing_kept"] == len(adsb)


def test_min_nic_does_not_filter_on_the_0_2x_figure_of_merit():
    # CAT021 0.23 reports: I021/090 PA 3 and 7, no NUCp/NIC and no NACp (spec: AC/MN/DC/PA only); PA is not
    # documented on NUCp's scale, so --min-nic 6 and --min-nacp 7 keep both and say why
    frame = pd.DataFrame({"time_of_day": [1.0, 2.0], "day": [0, 0], "latitude": [1.0, 1.1],
                          "longitude": [100.0, 100.1], "sac": [0, 0], "sic": [1, 1],
                          "fom_pa": pd.array([3, 7], dtype="Int64")})
    kept, removed = apply_filters(adsb_measurements(frame), min_nic=6, min_nacp=7)
    assert len(kept) == 2 and removed["nic_below_min"] == 0 and removed["nic_missing_kept"] == 2
    assert removed["nacp_missing_kept"] == 2
    warnings = filter_warnings(removed, 6, 7)
    assert len(warnings) == 2 and warnings[0].startswith("--min-nic 6: 2 ADS-B report(s) carry no NUCp/NIC")
    assert "figure of merit PA" in warnings[0] and warnings[1].startswith("--min-nacp 7: 2 ")
    assert filter_warnings(removed, None, None) == []


@pytest.mark.parametrize(("kw", "error", "words"), [
    ({"min_nic": 5.5}, TypeError, ["min_nic", "5.5"]),
    ({"min_nic": -1}, ValueError, ["min_nic", "-1", "0 to 15"]),
    ({"min_nacp": True}, TypeError, ["min_nacp", "True"]), ({"jump_kw": "x"}, TypeError, ["jump_kw", "str"]),
])
def test_bad_arguments_are_named(adsb, kw, error, words):
    with pytest.raises(error) as exc:
        apply_filters(adsb, **kw)
    assert all(w in str(exc.value) for w in words), str(exc.value)
    with pytest.raises(TypeError, match="meas: expected a pandas DataFrame, got NoneType"):
        apply_filters(None)
