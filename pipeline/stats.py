"""What a recording holds: records per category and SAC/SIC, time span, aircraft, skipped blocks."""

from __future__ import annotations

import pandas as pd


def _span(frame: pd.DataFrame) -> tuple[float, float]:
    t = frame["day"].to_numpy() * 86400.0 + frame["time_of_day"].to_numpy()
    t = t[~pd.isna(t)]
    return (float(t.min()), float(t.max())) if len(t) else (float("nan"), float("nan"))


def _clock(seconds: float) -> str:
    if pd.isna(seconds):
        return "-"
    day, rem = divmod(seconds, 86400.0)
    h, rem = divmod(rem, 3600.0)
    m, s = divmod(rem, 60.0)
    prefix = f"+{int(day)}d " if day else ""
    return f"{prefix}{int(h):02d}:{int(m):02d}:{s:06.3f}"


def stats_tables(frames: dict[int, pd.DataFrame], errors: pd.DataFrame,
                 ignored: pd.DataFrame | list[pd.DataFrame] | None = None) -> dict[str, pd.DataFrame]:
    """Tables: per category, per category and SAC/SIC, skipped blocks grouped by reason, and blocks of
    categories not decoded (``Recording.ignored``, one frame or one per input)."""
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
    parts = [f for f in (ignored if isinstance(ignored, list) else [ignored]) if f is not None and len(f)]
    other = (pd.concat(parts).groupby("category", as_index=False)[["blocks", "bytes"]].sum() if parts
             else pd.DataFrame(columns=["category", "blocks", "bytes"]))
    return {"categories": pd.DataFrame(per_cat), "sources": pd.DataFrame(per_src), "skipped": reasons,
            "other": other}


def format_stats(tables: dict[str, pd.DataFrame]) -> str:
    """The tables as plain text for the terminal."""
    parts = []
    for title, key in (("Records per category", "categories"), ("Records per SAC/SIC", "sources"),
                       ("Skipped blocks", "skipped"), ("Blocks of categories not decoded", "other")):
        if key not in tables:
            continue
        t = tables[key]
        parts.append(f"{title}:\n" + ("  none" if t.empty else t.to_string(index=False)))
    return "\n\n".join(parts) + "\n"
