"""The documented requirement ids a preset may name: what each measures, its kind and unit, and the
parameters it takes (name -> type, and which are required)."""

from __future__ import annotations

from dataclasses import dataclass, field

PROPORTION = "proportion"  # successes / trials, Clopper-Pearson interval
ERROR = "error"  # a statistic of per-report errors, bootstrap interval over aircraft
SIGNED = "signed"  # a fitted signed quantity (bias): its threshold applies to its magnitude
RATE = "rate"  # a count per scan or per interval


@dataclass(frozen=True)
class RequirementType:
    """One requirement id: its kind, unit, the statistic behind it, its parameters and what it measures."""

    kind: str
    unit: str
    description: str
    statistic: str = ""
    parameters: dict[str, type | tuple] = field(default_factory=dict)
    required: tuple[str, ...] = ()


_TOLERANCE_FT = {"tolerance_ft": float}
_PD = {"interval_s": float, "scope": ("global", "per_target")}

def _share(description: str, **kw) -> RequirementType:
    """A proportion requirement (successes / trials)."""
    return RequirementType(PROPORTION, "fraction", description, **kw)


def _error(unit: str, description: str, statistic: str) -> RequirementType:
    """A statistic of per-report errors."""
    return RequirementType(ERROR, unit, description, statistic)


CATALOGUE: dict[str, RequirementType] = {
    "pd": _share("probability of detection/update: expected update intervals of interval_s (else the "
                 "radar's scan period) that hold at least one report; scope 'global' pools every interval, "
                 "'per_target' holds for each aircraft", parameters=_PD),
    "long_gaps": _share("share of gaps between consecutive reports with min_gap_s <= gap < max_gap_s (no "
                        "upper limit when max_gap_s is absent)",
                        parameters={"min_gap_s": float, "max_gap_s": float}, required=("min_gap_s",)),
    "rms_m": _error("m", "horizontal position error, RMS", "rms"),
    "mean_m": _error("m", "horizontal position error, mean", "mean"),
    "p95_m": _error("m", "horizontal position error, 95th percentile", "p95"),
    "p99_m": _error("m", "horizontal position error, 99th percentile", "p99"),
    "max_m": _error("m", "horizontal position error, maximum (no interval)", "max"),
    "along_rms_m": _error("m", "along-track position error, RMS", "rms"),
    "across_rms_m": _error("m", "across-track position error, RMS", "rms"),
    "latency_p95_s": _error("s", "latency (along-track error / speed), 95th percentile", "p95"),
    "range_bias_m": RequirementType(SIGNED, "m", "radar slant range bias (fitted)"),
    "range_gain_ppm": RequirementType(SIGNED, "ppm", "radar range gain (fitted; 1 m/NM = 540 ppm)"),
    "azimuth_bias_deg": RequirementType(SIGNED, "deg", "radar azimuth bias (fitted)"),
    "time_bias_s": RequirementType(SIGNED, "s", "time stamp bias (fitted)"),
    "range_sd_m": _error("m", "radar range random error, standard deviation", "sd"),
    "azimuth_sd_deg": _error("deg", "radar azimuth random error, standard deviation", "sd"),
    "mode3a_present": _share("reports with a Mode 3/A code"),
    "mode3a_valid": _share("Mode 3/A codes marked valid and not garbled"),
    "mode3a_correct": _share("reports with a validated, ungarbled Mode 3/A code equal to the reference's, of "
                             "the reports whose reference code is known"),
    "mode3a_false": _share("validated, ungarbled Mode 3/A codes differing from the reference's"),
    "modec_present": _share("reports with a Mode C pressure altitude"),
    "modec_valid": _share("Mode C altitudes marked valid and not garbled"),
    "modec_correct": _share("reports with a validated, ungarbled Mode C within tolerance_ft of the "
                            "reference's, of the reports whose reference altitude is known",
                            parameters=_TOLERANCE_FT, required=("tolerance_ft",)),
    "modec_false": _share("validated, ungarbled Mode C outside tolerance_ft of the reference's",
                          parameters=_TOLERANCE_FT, required=("tolerance_ft",)),
    "address_correct": _share("Mode S addresses equal to the reference's"),
    "address_false": _share("Mode S addresses differing from the reference's"),
    "callsign_correct": _share("call signs equal to the reference's"),
    "callsign_false": _share("call signs differing from the reference's"),
    "identification_correct": _share("reports whose identity (address, call sign, validated Mode 3/A: "
                                     "whichever they carry and the reference knows) matches the reference "
                                     "in every item, of the reports with such an item"),
    "identification_false": _share("reports with an identity item (address, call sign, validated Mode 3/A) "
                                   "that differs from the reference's, of the same reports"),
    "false_reports": _share("reports with no reference aircraft within distance_m",
                            parameters={"distance_m": float}, required=("distance_m",)),
    "false_reports_per_scan": RequirementType(RATE, "per scan", "false target reports per antenna scan: "
                                              "reports with no reference aircraft within distance_m (by "
                                              "default the association gate, 2 NM)",
                                              parameters={"distance_m": float}),
    "split_reports": _share("updates (scans) of an aircraft holding a split plot: a second report not an "
                            "exact repeat, or one marked split (I048/030 code 3)"),
    "multiple_reports": _share("updates (scans or intervals) of an aircraft holding more than one report "
                               "(I048/030 code 3 counted too)"),
    "dubious": _share("reports physically implausible against their aircraft's report before it: speed, "
                      "acceleration, turn rate or vertical rate beyond the limits",
                      parameters={"max_speed_kt": float, "max_accel_mps2": float, "max_turn_dps": float,
                                  "max_vertical_ftps": float}),
    "psr_ssr_association": _share("updates (scans) of an aircraft in which PSR and SSR both detected it that "
                                  "hold a combined PSR + SSR plot (I048/020 TYP 3, 6, 7)"),
    "velocity_correct": _share("reported velocities within the tolerance of the reference's (the larger of "
                               "tolerance_mps and tolerance_fraction x speed)",
                               parameters={"tolerance_mps": float, "tolerance_fraction": float},
                               required=("tolerance_mps",)),
    "extra_tracks": _share("intervals of interval_s of an aircraft holding more than one test track number",
                           parameters={"interval_s": float}),
    "track_continuity": RequirementType(RATE, "per aircraft", "changes of an aircraft's main test track "
                                        "number from one interval of interval_s to the next, per aircraft",
                                        parameters={"interval_s": float}),
    "coasting_correct": _share("track reports whose coasting flag (I062/080 CST) agrees with the reference: "
                               "set when no reference sensor detected the aircraft in the last window_s, "
                               "clear when one did", parameters={"window_s": float}),
}
