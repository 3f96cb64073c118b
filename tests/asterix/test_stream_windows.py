"""asterix.stream.plan_windows/decode_window: a raw stream's windows decoded apart give the records, days,
timestamps and block numbers iter_read gives, whatever the window size (midnight inside a window or between
two), and a recording whose windows cannot decode apart is left to iter_read."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest
from dataset_data import ADSB, DAY, RADAR, midnight_recording

import msdc.asterix as asterix
from msdc.asterix.stream import decode_window, plan_windows


@pytest.fixture(scope="module")
def midnight(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("win") / "midnight.ast"
    midnight_recording(path, 6000)
    return path


@pytest.mark.parametrize("which,chunk", [("midnight", 3_000), ("midnight", 7_001), ("midnight", 1 << 20),
                                         ("radar", 7_001), ("adsb", 40_000)])
def test_windows_decode_as_iter_read(midnight, which, chunk):
    path = {"midnight": midnight, "radar": RADAR, "adsb": ADSB}[which]
    streamed = list(asterix.iter_read(path, chunk=chunk, date=DAY))
    with ThreadPoolExecutor(2) as pool:
        plan, windows = plan_windows(path, pool, chunk=chunk, date=DAY)
        apart = list(pool.map(lambda w: decode_window(path, plan, w), windows))
    for cat in streamed[0].frames:
        want = pd.concat([r.frames[cat] for r in streamed], ignore_index=True)
        got = pd.concat([r.frames[cat] for r in apart], ignore_index=True)
        pd.testing.assert_frame_equal(got, want)
    if which == "midnight":
        assert sorted(want["day"].unique()) == [0, 1]  # the midnight this test is about


def test_a_pcap_is_left_to_iter_read(tmp_path):
    from container_bytes import pcap_file, udp_frame

    data = RADAR.read_bytes()
    first = int.from_bytes(data[1:3], "big")  # the first data block, by its LEN
    path = tmp_path / "r.pcap"
    path.write_bytes(pcap_file([(1_795_852_800, 0, udp_frame(data[:first]))])[0])  # 2026-11-28 08:00 UTC
    with ThreadPoolExecutor(1) as pool:
        assert plan_windows(path, pool, chunk=1000, date=DAY) is None
