"""What a recording holds: records per category and SAC/SIC, time spans, aircraft per sensor, skipped blocks.

Times are UTC date-times when the recording's date is known (timestamps present), HH:MM:SS otherwise
(``+Nd`` past the first day); never seconds of day.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

# "(record at offset 1234)", "at offset 0x1f": the place, not the reason
_OFFSET = re.compile(r"\s*\((?:record )?at offset (?:0x[0-9a-fA-F]+|\d+)\)"
                     r"|\s*\bat offset (?:0x[0-9a-fA-F]+|\d+)")


def reason_kind(reason: str) -> str:
    """A skipped block's reason without the offset embedded in it, so equal reasons group together."""
    return _OFFSET.sub("", str(reason)).strip()


def _seconds(frame: pd.DataFrame) -> np.ndarray:
    t = frame["day"].to_numpy(dtype=float, na_value=np.nan) * 86400.0
    return t + frame["time_of_day"].to_numpy(dtype=float, na_value=np.nan)


def clock(seconds: float) -> str:
    """HH:MM:SS of seconds since midnight of the first day (with "+Nd " past it); "-" when missing."""
    if not np.isfinite(seconds):
        return "-"
    day, rem = divmod(int(seconds // 1), 86400)
    text = f"{rem // 3600:02d}:{rem % 3600 // 60:02d}:{rem % 60:02d}"
    return f"+{day}d {text}" if day else text


def _span(frame: pd.DataFrame) -> tuple[str, str, float]:
    """Start and end as text (UTC date-time when timestamps are known, else HH:MM:SS) and the duration."""
    t = _seconds(frame)
    ok = np.isfinite(t)
    if not ok.any():
        return "-", "-", float("nan")
    first, last = int(np.argmin(np.where(ok, t, np.inf))), int(np.argmax(np.where(ok, t, -np.inf)))
    duration = float(t[last] - t[first])
    stamps = frame["timestamp"] if "timestamp" in frame.columns else None
    if stamps is not None and stamps.notna().iloc[[first, last]].all():
        start, end = stamps.iloc[first], stamps.iloc[last]
        fmt = "%Y-%m-%d %H:%M:%S"
        end_text = end.strftime("%H:%M:%S" if end.date() == start.date() else fmt)
        return start.strftime(fmt), end_text, duration
    return clock(t[first]), clock(t[last]), duration


def _aircraft(frame: pd.DataFrame, cat: int) -> list[dict]:
    """One row per sensor and aircraft (address, else call sign): call sign(s), reports and time span."""
    if frame.empty:
        return []
    address = frame["address"].astype(object)
    key = address.where(address.notna(), "cs:" + frame["callsign"].astype(object))
    rows = []
    for (sac, sic, _), g in frame.assign(_key=key).groupby(["sac", "sic", "_key"], dropna=True, observed=True,
                                                          sort=True):
        start, end, duration = _span(g)
        callsigns = sorted({str(c).strip() for c in g["callsign"].dropna().unique()})
        address = g["address"].dropna()
        rows.append({"category": cat, "sac": sac, "sic": sic,
                     "address": str(address.iloc[0]) if len(address) else "-",
                     "callsign": ", ".join(callsigns) or "-", "records": len(g), "start": start, "end": end,
                     "duration_min": round(duration / 60.0, 1)})
    return rows


def stats_tables(frames: dict[int, pd.DataFrame], errors: pd.DataFrame,
                 ignored: pd.DataFrame | list[pd.DataFrame] | None = None) -> dict[str, pd.DataFrame]:
    """Tables: per category, per category and SAC/SIC, aircraft per sensor, skipped blocks by reason, and
    blocks of categories not decoded (``Recording.ignored``, one frame or one per input)."""
    per_cat, per_src, aircraft = [], [], []
    for cat, f in sorted(frames.items()):
        start, end, duration = _span(f)
        per_cat.append({"category": cat, "records": len(f), "start": start, "end": end,
                        "duration_min": round(duration / 60.0, 1), "addresses": f["address"].nunique(),
                        "callsigns": f["callsign"].nunique()})
        for (sac, sic), g in f.groupby(["sac", "sic"], dropna=False, observed=True):
            s, e, _ = _span(g)
            per_src.append({"category": cat, "sac": sac, "sic": sic, "records": len(g), "start": s, "end": e,
                            "addresses": g["address"].nunique(), "callsigns": g["callsign"].nunique()})
        aircraft += _aircraft(f, cat)
    columns = ["category", "reason", "blocks", "bytes", "first_offset"]
    if len(errors):
        kinds = errors.assign(reason=errors["reason"].map(reason_kind))
        reasons = (kinds.groupby(["category", "reason"], dropna=False)
                   .agg(blocks=("offset", "size"), bytes=("length", "sum"), first_offset=("offset", "min"))
                   .reset_index().sort_values(["blocks", "first_offset"], ascending=[False, True]))
    else:
        reasons = pd.DataFrame(columns=columns)
    parts = [f for f in (ignored if isinstance(ignored, list) else [ignored]) if f is not None and len(f)]
    other = (pd.concat(parts).groupby("category", as_index=False)[["blocks", "bytes"]].sum() if parts
             else pd.DataFrame(columns=["category", "blocks", "bytes"]))
    return {"categories": pd.DataFrame(per_cat), "sources": pd.DataFrame(per_src),
            "aircraft": pd.DataFrame(aircraft), "skipped": reasons[columns].reset_index(drop=True),
            "other": other}


def format_stats(tables: dict[str, pd.DataFrame]) -> str:
    """The tables as plain text for the terminal."""
    parts = []
    for title, key in (("Records per category", "categories"), ("Records per SAC/SIC", "sources"),
                       ("Aircraft per sensor (address, call signs, time span)", "aircraft"),
                       ("Skipped blocks by reason", "skipped"),
                       ("Blocks of categories not decoded", "other")):
        if key not in tables:
            continue
        t = tables[key]
        parts.append(f"{title}:\n" + ("  none" if t.empty else t.to_string(index=False)))
    return "\n\n".join(parts) + "\n"
