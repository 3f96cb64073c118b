"""Decoding a batch of received datagrams in one call of the msdc.asterix kernel: each datagram is one
segment of an in-memory recording (framed carefully on its own, so that the blocks before a damaged one are
kept), dated by its arrival (wall clock) time; the records, errors and status messages are folded into the
LiveState per feed."""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from msdc.asterix import kernel
from msdc.asterix.errors import REASONS

log = logging.getLogger("msdc.live")

SECONDS_PER_DAY = 86400
# the reasons of errors inside a data block that framed (its records do not decode): "decode_errors";
# any other error is a datagram that does not frame into data blocks: "unframed"
RECORD_REASONS = tuple(REASONS[code] for code in (
    kernel.E_PAST_END, kernel.E_UNDEFINED_FRN, kernel.E_UNDEFINED_SUB, kernel.E_EXPLICIT_LEN,
    kernel.E_EMPTY_FSPEC, kernel.E_EMPTY_BLOCK, kernel.E_RFS, kernel.E_NO_UAP))
# status categories -> the category of the reports of the same sensor (CAT034 north markers go with CAT048
# plots, CAT002 with CAT001, CAT019 with CAT020 multilateration, CAT023 with CAT021 ADS-B, CAT065 with
# CAT062 tracks); CAT025 and CAT063 are counted under their own id only
STATUS_OF = {34: 48, 2: 1, 19: 20, 23: 21, 65: 62, 25: None, 63: None}
# CAT010 records by kind (sorted; "": status messages and reports of kinds msdc does not measure, counted as
# "010:SAC/SIC", which gives its kinds' panels their last status and no panel of its own)
CAT010_KINDS = np.array(["", "mlat", "smr"])
# the decoded columns the live counters and the recent reports need (all of a category when it has them)
COLUMNS = ("sac", "sic", "time_of_day", "mode3a", "mode3a_v", "mode3a_g", "flight_level", "flight_level_v",
           "flight_level_g", "rho_nm",
           "theta_deg", "latitude", "longitude", "address", "callsign", "track_number", "ground_speed_kt",
           "gbs", "flight_status", "rab", "nacp", "nucp_nic", "geometric_height_ft", "track_angle_deg",
           "heading_deg", "message_type", "typ", "sim", "rho_m", "x_m", "y_m", "vx_ms", "vy_ms", "sigma_x_m",
           "sigma_y_m")
# the categories whose reports become measurement rows (the recent reports, the sensors' figures, the map);
# the records of the others are counted (CAT001 plots, CAT062 system tracks)
MEASURED = (48, 21, 10, 20)


@dataclass(frozen=True)
class Datagram:
    """One received UDP datagram: the feed it came on, its arrival time (time.time()), its bytes and its
    sender (for the recording's IP and UDP headers)."""

    feed: int  # index of the feed in the listener's list
    wall_s: float
    data: bytes
    source: tuple[str, int] = ("0.0.0.0", 0)


class BatchDecoder:
    """Decodes batches of datagrams into a LiveState; ``sensors`` (the sensor table) places radar plots,
    ``reports`` keeps the reports for LiveState.recent (the monitor page reads them)."""

    def __init__(self, state, feeds: list[str], *, sensors: pd.DataFrame | None = None,
                 editions: dict | None = None, reports: bool = True):
        from msdc.asterix.categories import DECODABLE
        from msdc.asterix.reader import KNOWN_COLUMNS

        self.state, self.feeds, self.sensors = state, list(feeds), sensors
        self.editions = dict(editions or {})
        self.categories = DECODABLE
        self.columns = [c for c in COLUMNS if c in KNOWN_COLUMNS]
        self.reports = reports
        self.records = 0  # records decoded so far, every feed
        self.batches = 0

    def decode(self, batch: list[Datagram]) -> None:
        """Decode one batch and fold it into the state; never raises for bad bytes (a batch the decoder fails
        on is counted as decode errors of its datagrams and logged)."""
        if not batch:
            return
        from msdc.asterix import decode_buffer
        from msdc.asterix.containers import Segments

        lens = np.fromiter((len(d.data) for d in batch), np.int64, len(batch))
        stop = np.cumsum(lens)
        start = stop - lens
        wall = np.fromiter((d.wall_s for d in batch), np.float64, len(batch))
        feed = np.fromiter((d.feed for d in batch), np.int64, len(batch))
        buf = np.frombuffer(b"".join(d.data for d in batch), np.uint8)
        day = (wall // SECONDS_PER_DAY).astype(np.int64)
        seg = Segments("pcap", start, stop, day, wall - day * SECONDS_PER_DAY, True, False, 0, [])
        self.batches += 1
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rec = decode_buffer(buf, seg, editions=self.editions, categories=self.categories,
                                    columns=self.columns)
        except Exception as exc:  # the kernel's own failure: counted and said, never the end of listening
            log.error("a batch of %d datagrams could not be decoded: %s", len(batch), exc)
            self.state.decoded(failed_batch_counts(feed, lens, self.feeds), None, {})
            return
        counts: dict[str, dict] = {
            name: {"framed": 0, "unframed": 0, "empty": 0, "decode_errors": 0, "records": {},
                   "last_record_wall_s": {}}
            for name in {self.feeds[f] for f in np.unique(feed)}}
        unframed = self._errors(rec.errors, stop, feed, counts)
        self._datagrams(lens, unframed, feed, counts)
        status: dict[str, float] = {}
        parts = []
        for cat, frame in rec.frames.items():
            frame = self._without_odd_sources(frame, stop, feed, counts)
            if not len(frame):
                continue
            row_dgram = np.searchsorted(stop, frame["offset"].to_numpy(np.int64), side="right")
            self._count(cat, frame, feed[row_dgram], wall[row_dgram], counts)
            self.records += len(frame)
            if cat == 10 and "message_type" in frame:  # its status messages, under "010:SAC/SIC"
                from msdc.pipeline.model.multilateration import TARGET_REPORT

                said = (frame["message_type"] != TARGET_REPORT).fillna(False).to_numpy(bool)
                if said.any():
                    self._status(cat, frame[said], wall[row_dgram][said], status)
            if cat in STATUS_OF:
                self._status(cat, frame, wall[row_dgram], status)
            elif self.reports and cat in MEASURED:
                rows = report_rows(cat, frame.reset_index(drop=True), self.sensors, rec.date)
                if rows is not None and len(rows):
                    at = row_dgram[rows.index.to_numpy()]
                    rows["wall_s"] = wall[at]
                    rows["feed"] = np.array(self.feeds, dtype=object)[feed[at]]
                    parts.append(rows.reset_index(drop=True))
        reports = pd.concat(parts, ignore_index=True) if len(parts) > 1 else (parts[0] if parts else None)
        self.state.decoded(counts, reports, status)

    def _without_odd_sources(self, frame: pd.DataFrame, stop: np.ndarray, feed: np.ndarray,
                             counts: dict) -> pd.DataFrame:
        """The frame without the records naming another data source than their block (and those after them
        in it: model.odd_sources), which damage inside a block makes; each such block counted as a decode
        error of its feed (its made-up sensors would have panels of their own)."""
        from msdc.pipeline.model.odd_sources import odd_source_mask

        odd = odd_source_mask(frame)
        if not odd.any():
            return frame
        damaged = frame.loc[odd].drop_duplicates("block")
        at = np.searchsorted(stop, damaged["offset"].to_numpy(np.int64), side="right")
        for f, n in zip(*np.unique(feed[at], return_counts=True), strict=True):
            counts[self.feeds[f]]["decode_errors"] += int(n)
        return frame[~odd]

    def _errors(self, errors: pd.DataFrame, stop: np.ndarray, feed: np.ndarray, counts: dict) -> np.ndarray:
        """Unframed datagrams (each counted once) and blocks whose records do not decode, per feed; the
        unframed datagrams' places in the batch."""
        if not len(errors):
            return np.zeros(0, np.int64)
        at = np.searchsorted(stop, errors["offset"].to_numpy(np.int64), side="right")
        in_record = errors["reason"].astype(str).str.startswith(RECORD_REASONS).to_numpy()
        for f, n in zip(*np.unique(feed[at[in_record]], return_counts=True), strict=True):
            counts[self.feeds[f]]["decode_errors"] += int(n)
        unframed = np.unique(at[~in_record])
        for f, n in zip(*np.unique(feed[unframed], return_counts=True), strict=True):
            counts[self.feeds[f]]["unframed"] += int(n)
        return unframed

    def _datagrams(self, lens: np.ndarray, unframed: np.ndarray, feed: np.ndarray, counts: dict) -> None:
        """Each datagram of the batch counted once per feed: empty (no byte), else unframed (counted by
        _errors), else framed; so that a feed's packets add up."""
        empty = lens == 0
        framed = ~empty
        framed[unframed] = False
        for key, which in (("empty", empty), ("framed", framed)):
            for f, n in zip(*np.unique(feed[which], return_counts=True), strict=True):
                counts[self.feeds[f]][key] += int(n)

    def _count(self, cat: int, frame: pd.DataFrame, row_feed: np.ndarray, row_wall: np.ndarray,
               counts: dict) -> None:
        """Records per feed and sensor ("CCC:SAC/SIC"; "?" for a missing SAC or SIC), and when the latest
        of them arrived: a sensor whose reports make no measurement rows is still heard."""
        none = np.full(len(frame), np.nan)
        sac = frame["sac"].to_numpy("float64", na_value=np.nan) if "sac" in frame else none
        sic = frame["sic"].to_numpy("float64", na_value=np.nan) if "sic" in frame else none
        kind = np.zeros(len(frame), np.int64)  # CAT010: its measurements' sensor id, as report_rows makes it
        if cat == 10:
            from msdc.pipeline.model.multilateration import report_kinds

            kind = np.searchsorted(CAT010_KINDS, report_kinds(frame, 10)[0].astype(str))
        key = (row_feed * 10_000_000 + kind * 1_000_000 + np.nan_to_num(sac, nan=999) * 1000
               + np.nan_to_num(sic, nan=999))
        keys, inverse, n = np.unique(key.astype(np.int64), return_inverse=True, return_counts=True)
        latest = np.full(len(keys), -np.inf)
        np.maximum.at(latest, inverse, row_wall)
        for k, count, t in zip(keys.tolist(), n.tolist(), latest.tolist(), strict=True):
            f, a, b = k // 10_000_000, k // 1000 % 1000, k % 1000
            sensor = f"{cat:03d}:{'?' if a == 999 else a}/{'?' if b == 999 else b}"
            if k // 1_000_000 % 10:
                sensor += f":{CAT010_KINDS[k // 1_000_000 % 10]}"
            feed = counts[self.feeds[f]]
            feed["records"][sensor] = feed["records"].get(sensor, 0) + count
            feed["last_record_wall_s"][sensor] = max(t, feed["last_record_wall_s"].get(sensor, -np.inf))

    @staticmethod
    def _status(cat: int, frame: pd.DataFrame, row_wall: np.ndarray, status: dict[str, float]) -> None:
        """The latest arrival time of each sensor's status messages, under its own id and its reports'."""
        if "sac" not in frame or "sic" not in frame:
            return
        pairs = pd.DataFrame({"sac": frame["sac"].to_numpy(), "sic": frame["sic"].to_numpy(), "w": row_wall})
        for (sac, sic), w in pairs.groupby(["sac", "sic"])["w"].max().items():
            for c in (cat, STATUS_OF.get(cat)):
                if c is not None:
                    key = f"{c:03d}:{int(sac)}/{int(sic)}"
                    status[key] = max(status.get(key, float("-inf")), float(w))


def failed_batch_counts(feed: np.ndarray, lens: np.ndarray, names: list[str]) -> dict[str, dict]:
    """The counts of a batch the decoder failed on, per feed: each datagram a decode error and, not framed,
    unframed (an empty one: empty only), so that the feed's packets still add up."""
    counts = {}
    for f in np.unique(feed):
        here = feed == f
        empty = int((here & (lens == 0)).sum())
        counts[names[f]] = {"decode_errors": int(here.sum()) - empty, "unframed": int(here.sum()) - empty,
                            "empty": empty}
    return counts


def report_rows(cat: int, frame: pd.DataFrame, sensors: pd.DataFrame | None, date) -> pd.DataFrame | None:
    """The measurement rows of one decoded frame, indexed by the frame's rows (those without a time, or an
    ADS-B report without a position, have none); CAT048 plots of radars not in ``sensors`` get no position
    but keep their other columns; CAT010/CAT020 reports with only Cartesian or polar positions need their
    sensor's reference point in ``sensors`` (without it they have no row, and are counted only). With
    mode3a_valid and modec_valid: the V and G bits of the Mode 3/A code and flight level (I048/070 and
    I048/090, I010/060 and I010/090, I020/070 and I020/090) clear -> valid, either set -> not; <NA> where
    the report does not say (CAT021 never does)."""
    from msdc.pipeline.model.measurements import measurement_rows, no_plot, sensor_id
    from msdc.pipeline.model.schema import conform
    from msdc.pipeline.model.time import absolute_time

    if cat in (10, 20):  # placed by their WGS-84 position or the sensor file's reference point
        from msdc.pipeline.model.measurements import local_measurement_rows

        local = local_measurement_rows(frame if cat == 10 else None, frame if cat == 20 else None, sensors,
                                       date=date)
        if not local.parts:
            return None
        rows = local.parts[0]
        source = frame.loc[rows.index]
        rows["mode3a_valid"] = _valid(source, "mode3a")
        rows["modec_valid"] = _valid(source, "flight_level")
        return rows
    if cat == 21:
        _, rows = measurement_rows(None, frame, date=date)
        if rows is None:
            return None
        rows["mode3a_valid"] = pd.array([pd.NA] * len(rows), dtype="boolean")
        rows["modec_valid"] = pd.array([pd.NA] * len(rows), dtype="boolean")
        return rows
    known = np.zeros(len(frame), bool)
    if sensors is not None and len(sensors):
        keys = pd.MultiIndex.from_arrays([frame["sac"].astype("Int64"), frame["sic"].astype("Int64")])
        known = keys.isin(pd.MultiIndex.from_frame(sensors[["sac", "sic"]].astype("Int64")))
    parts = []
    if known.any():
        rows, _ = measurement_rows(frame[known], None, sensors, date=date)
        if rows is not None:
            parts.append(rows)
    unknown = ~known & ~no_plot(frame, 48)  # a radar tracker's own updates and simulated plots: no rows
    if unknown.any():
        bare = frame[unknown]
        cols = {"time": absolute_time(bare, date), "sac": bare["sac"], "sic": bare["sic"],
                "sensor_id": sensor_id(48, bare["sac"], bare["sic"]).set_axis(bare.index),
                "sensor_kind": pd.Series("radar", index=bare.index)}
        for name in ("flight_level", "mode3a", "address", "callsign", "track_number", "rho_nm", "theta_deg"):
            if name in bare:
                cols[name] = bare[name]
        bare_rows = conform(pd.DataFrame(cols, index=bare.index))
        parts.append(bare_rows[bare_rows["time"].notna()])
    if not parts:
        return None
    rows = pd.concat(parts).sort_index() if len(parts) > 1 else parts[0]
    source = frame.loc[rows.index]
    rows["mode3a_valid"] = _valid(source, "mode3a")
    rows["modec_valid"] = _valid(source, "flight_level")
    return rows


def _valid(frame: pd.DataFrame, code: str) -> pd.arrays.BooleanArray:
    """The code validated and not garbled (its V and G bits clear, as the evaluation's ``mode3a_valid`` and
    ``modec_valid`` judge it) -> True, either bit set -> False; <NA> where the item is absent."""
    v_bit, g_bit = f"{code}_v", f"{code}_g"
    if v_bit not in frame:
        return pd.array([pd.NA] * len(frame), dtype="boolean")
    v = frame[v_bit].astype("Int64").to_numpy(dtype="float64", na_value=np.nan)
    g = (frame[g_bit].astype("Int64").to_numpy(dtype="float64", na_value=0.0) if g_bit in frame
         else np.zeros(len(frame)))
    out = pd.array((v == 0) & (g == 0), dtype="boolean")
    out[np.isnan(v)] = pd.NA
    return out
