"""Optional ADS-B report filters (all off by default): position jumps, low NIC, low NACp.

Filters run in a fixed order (jumps, then NIC, then NACp), each on what the previous one left, so a report
is counted once, by the first filter that removes it. NIC uses ``nucp_nic``, which holds NUCp for MOPS
version 0 reports and NIC for versions 1/2: choose ``min_nic`` for the version in the data. Reports whose
NIC (or NACp) is missing are kept, and counted under ``nic_missing_kept`` (``nacp_missing_kept``) when that
minimum is set, among the reports that reach that filter. CAT021 0.2x reports carry neither: their figure of
merit PA (``fom_pa``) is on a scale not documented as NUCp's or NACp's, so no filter reads it and they are
kept (``filter_warnings`` says so).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.jumps import JUMP_FLAG_COLUMNS, JUMP_INPUTS, detect_jumps
from msdc.pipeline.quality.checks import check_frame, check_indicator, check_options

FILTER_KEYS = ["jumps", "nic_below_min", "nacp_below_min", "nic_missing_kept", "nacp_missing_kept"]


def _below(meas: pd.DataFrame, column: str, minimum: int | None) -> tuple[pd.Series, int]:
    """Rows below the minimum (missing values are not below) and how many values are missing."""
    if minimum is None:
        return pd.Series(False, index=meas.index), 0
    values = pd.to_numeric(meas[column], errors="coerce") if column in meas else pd.Series(
        float("nan"), index=meas.index)
    return (values < minimum).fillna(False).astype(bool), int(values.isna().sum())


def apply_filters(meas: pd.DataFrame, *, drop_jumps: bool = False, min_nic: int | None = None,
                  min_nacp: int | None = None,
                  jump_kw: dict | None = None) -> tuple[pd.DataFrame, dict[str, int]]:
    """Measurements with the ADS-B reports that fail the chosen filters removed (radar rows untouched,
    order kept, index reset), and the count per key of FILTER_KEYS."""
    check_frame("meas", meas, ("sensor_kind",))
    check_indicator("min_nic", min_nic)
    check_indicator("min_nacp", min_nacp)
    check_options("jump_kw", jump_kw)
    is_adsb = (meas["sensor_kind"] == "adsb").to_numpy(bool)
    if not drop_jumps and min_nic is None and min_nacp is None:  # nothing to remove: no copy
        return meas.reset_index(drop=True), dict.fromkeys(FILTER_KEYS, 0)
    read = [c for c in (*JUMP_INPUTS, *JUMP_FLAG_COLUMNS, "nucp_nic", "nacp") if c in meas]
    kept, removed = _filter_adsb(meas[read][is_adsb], drop_jumps, min_nic, min_nacp, jump_kw)
    keep = ~is_adsb
    keep[np.flatnonzero(is_adsb)[kept]] = True
    return (meas.reset_index(drop=True) if keep.all() else meas[keep].reset_index(drop=True)), removed


def _filter_adsb(adsb_meas: pd.DataFrame, drop_jumps: bool, min_nic: int | None, min_nacp: int | None,
                 jump_kw: dict | None) -> tuple[np.ndarray, dict[str, int]]:
    """Which ADS-B rows pass (by position) and the count removed per filter."""
    removed = dict.fromkeys(FILTER_KEYS, 0)
    kept = adsb_meas.reset_index(drop=True)
    if drop_jumps and len(kept):
        jump = detect_jumps(kept, **(jump_kw or {}))
        removed["jumps"] = int(jump.sum())
        kept = kept[~jump.to_numpy()]
    low_nic, removed["nic_missing_kept"] = _below(kept, "nucp_nic", min_nic)
    removed["nic_below_min"] = int(low_nic.sum())
    kept = kept[~low_nic.to_numpy()]
    low_nacp, removed["nacp_missing_kept"] = _below(kept, "nacp", min_nacp)
    removed["nacp_below_min"] = int(low_nacp.sum())
    kept = kept[~low_nacp.to_numpy()]
    passed = np.zeros(len(adsb_meas), bool)
    passed[kept.index.to_numpy()] = True
    return passed, removed


def filter_warnings(removed: dict[str, int], min_nic: int | None, min_nacp: int | None) -> list[str]:
    """One warning per minimum that kept reports for want of the indicator (``apply_filters``' counts)."""
    out = []
    for option, minimum, key, name in (("--min-nic", min_nic, "nic_missing_kept", "NUCp/NIC"),
                                       ("--min-nacp", min_nacp, "nacp_missing_kept", "NACp")):
        if minimum is not None and removed.get(key, 0):
            out.append(f"{option} {minimum}: {removed[key]} ADS-B report(s) carry no {name} and were kept "
                       "(CAT021 0.2x reports carry only the figure of merit PA, whose scale is not "
                       f"documented as {name}'s, so it is not filtered on)")
    return out
