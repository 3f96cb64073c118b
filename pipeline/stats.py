"""What a recording holds: records per category and SAC/SIC, time span, aircraft, skipped blocks."""

from __future__ import annotations

import pandas as pd

from pipeline.model.time import absolute_time, midnight, seconds_since


def _span(frame: pd.DataFrame) -> tuple[float, float]:
    """First and last time, in seconds from midnight of the frame's first day."""
    times = absolute_time(frame)
    ref = midnight(times)
    if ref is None:
        return float("nan"), float("nan")
    t = seconds_since(times.dropna(), ref)
    return float(t.min()), float(t.max())


def _clock(seconds: float) -> str:
    if pd.isna(seconds):
        return "-"
    day, rem = divmod(seconds, 86400.0)
    h, rem = divmod(rem, 3600.0)
    m, s = divmod(rem, 60.0)
    prefix = f"+{int(day)}d " if day else ""
    return f"{prefix}{int(h):02d}:{int(m):02d}:{s:06.3f}"


def stats_tables(frames: dict[int, pd.DataFrame], errors: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """Tables: per category, per category and SAC/SIC, and skipped blocks grouped by reason."""
    per_cat, per_src = [], []
    for cat, f in sorted(frames.items()):
        start, end = _span(f)
        per_cat.append({"category": cat, "records": len(f), "start": _clock(start), "end": _clock(end),
                        "duration_s": end - start, "addresses": f["address"].nunique(),
                        "callsigns": f["callsign"].nunique()})
        for (sac, sic), g in f.groupby(["sac", "sic"], dropna=False, observed=True):
            s, e = _span(g)
            per_src.append({"category": cat, "sac": sac, "sic": sic, "records": len(g), "start": _clock(s),
                            "end": _clock(e), "addresses": g["address"].nunique(),
                            "callsigns": g["callsign"].nunique()})
    reasons = (errors.groupby(["category", "reason"], dropna=False).agg(blocks=("offset", "size"),
                                                                      bytes=("length", "sum"),
                                                                      first_offset=("offset", "min"))
               .reset_index() if len(errors) else pd.DataFrame(
                   columns=["category", "reason", "blocks", "bytes", "first_offset"]))
    return {"categories": pd.DataFrame(per_cat), "sources": pd.DataFrame(per_src), "skipped": reasons}


def format_stats(tables: dict[str, pd.DataFrame]) -> str:
    """The tables as plain text for the terminal."""
    parts = []
    for title, key in (("Records per category", "categories"), ("Records per SAC/SIC", "sources"),
                       ("Skipped blocks", "skipped")):
        t = tables[key]
        parts.append(f"{title}:\n" + ("  none" if t.empty else t.to_string(index=False)))
    return "\n\n".join(parts) + "\n"
