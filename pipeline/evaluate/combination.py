"""``psr_ssr_association``: of the updates (antenna scans) of a reference aircraft in which both the
combined radar's PSR and its SSR detected it, the share in which the two were associated into one combined
plot (I048/020 TYP 3, 6 or 7) rather than reported as separate PSR-only and SSR-only plots."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.detection import update_period
from msdc.pipeline.evaluate.outcome import Outcome, share, withheld
from msdc.pipeline.evaluate.reference import associated
from msdc.pipeline.evaluate.scans import update_numbers

# I048/020 TYP (asterix-specs, CAT048): 1 single PSR, 2 single SSR, 3 SSR + PSR, 4 Mode S all-call,
# 5 Mode S roll-call, 6 Mode S all-call + PSR, 7 Mode S roll-call + PSR; 0 no detection
TYP_PSR_ONLY = (1,)
TYP_SSR_ONLY = (2, 4, 5)
TYP_COMBINED = (3, 6, 7)


def psr_ssr_association(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                        sensor: Sensor | None = None) -> Outcome:
    """Per reference aircraft, its associated plots grouped into updates (reports less than half a scan
    period apart: scans.update_groups); an update where PSR and SSR both saw the aircraft holds a combined
    plot, or a PSR-only and an SSR-only plot. The share of those updates holding a combined plot. Withheld
    where a failure could not be seen: no TYP, no PSR detection, no single PSR plot in the whole frame."""
    rid = "psr_ssr_association"
    if "typ" not in reports.columns:
        return withheld(rid, "the radar frame has no detection type (I048/020 TYP): PSR and SSR plots "
                             "cannot be told apart")
    if not np.isin(pd.to_numeric(reports["typ"], errors="coerce").to_numpy(float), TYP_PSR_ONLY).any():
        return withheld(rid, "no single PSR plot (I048/020 TYP 1) anywhere in the recording: the radar "
                             "reports none, or the recording leaves them out, so a PSR detection left "
                             "unassociated could not be seen")
    rep = associated(reports, reference, parameters)
    rep = rep[rep["ref_index"].to_numpy() >= 0]
    typ = pd.to_numeric(rep["typ"], errors="coerce").to_numpy(float)
    psr = np.isin(typ, TYP_PSR_ONLY + TYP_COMBINED)
    if not psr.any():
        return withheld(rid, "no PSR detection (I048/020 TYP 1, 3, 6 or 7) of a reference aircraft: not a "
                             "combined radar, or its PSR saw none of the reference aircraft")
    if sensor is None:
        raise ValueError(f"{rid} needs the sensor under test (its scan period)")
    period, said = update_period(rep, sensor)
    if not math.isfinite(period):
        return withheld(rid, "no scan period: no north markers and too few plots to estimate one")
    frame = pd.DataFrame({"aircraft": rep["ref_aircraft"].astype(str).to_numpy(object),
                          "t_s": rep["t_s"].to_numpy(float), "psr_only": np.isin(typ, TYP_PSR_ONLY),
                          "ssr_only": np.isin(typ, TYP_SSR_ONLY), "combined": np.isin(typ, TYP_COMBINED)})
    frame = frame.sort_values(["aircraft", "t_s"], kind="stable", ignore_index=True)
    frame["update"] = update_numbers(frame["aircraft"].to_numpy(object), frame["t_s"].to_numpy(float), period)
    per = frame.groupby(["aircraft", "update"], sort=True)[["psr_only", "ssr_only", "combined"]].any()
    both = per["combined"] | (per["psr_only"] & per["ssr_only"])
    if not both.any():
        return withheld(rid, "no update in which both the PSR and the SSR detected a reference aircraft")
    table = pd.DataFrame({"both": both, "combined": per["combined"] & both}).groupby(level="aircraft").sum()
    table = table.rename(columns={"both": "updates_both", "combined": "updates_combined"}).reset_index()
    return share(rid, int(per["combined"][both].sum()), int(both.sum()),
                 (said, f"{int(both.sum()):,} updates of {len(table):,} aircraft seen by both PSR and SSR"),
                 per_aircraft=table)
