"""What a scorecard says per sensor at a glance: its verdicts counted, the inconclusive rows that measured
nothing apart, and the requirements it fails with their sectors (the HTML report's first table and the
terminal's last lines)."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

VERDICTS = ("pass", "fail", "inconclusive")


@dataclass(frozen=True)
class SensorVerdicts:
    """One sensor's verdicts; ``failed`` maps a requirement to its failing (sector, scorecard row) pairs,
    rows numbered from 0 in the scorecard's order."""

    sensor: str
    counts: dict[str, int]
    not_measured: int
    failed: dict[str, list[tuple[str, int]]]


def sensor_verdicts(card: pd.DataFrame) -> list[SensorVerdicts]:
    """Per sensor of a scorecard (columns sensor, sector, requirement, value, verdict), in the order the
    sensors first appear: the counts of each verdict, how many inconclusive rows have no value (nothing
    was measured: an area without a sector, a withheld figure), and the failed requirements."""
    card = card.reset_index(drop=True)
    out = []
    for sensor, rows in card.groupby("sensor", sort=False):
        counts = rows["verdict"].value_counts()
        empty = int(((rows["verdict"] == "inconclusive") & rows["value"].isna()).sum())
        failed: dict[str, list[tuple[str, int]]] = {}
        for i, r in rows[rows["verdict"] == "fail"].iterrows():
            failed.setdefault(str(r["requirement"]), []).append((str(r["sector"]), int(i)))
        out.append(SensorVerdicts(str(sensor), {v: int(counts.get(v, 0)) for v in VERDICTS}, empty, failed))
    return out


def verdicts_text(card: pd.DataFrame) -> str:
    """The verdicts per sensor as lines for the terminal."""
    lines = []
    for s in sensor_verdicts(card):
        counts = ", ".join(f"{v} {s.counts[v]:,}" for v in VERDICTS)
        line = f"Verdicts of {s.sensor}: {counts} ({s.not_measured:,} of them not measured)"
        if s.failed:
            line += "; failed: " + "; ".join(f"{req} ({', '.join(sector for sector, _ in where)})"
                                              for req, where in s.failed.items())
        lines.append(line)
    return "\n".join(lines)
