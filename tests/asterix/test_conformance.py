"""Real records from ../shared/conformance decode to the values an independent decoder gave for them."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest
from asterix_bytes import SHARED

import msdc.asterix as asterix

CONF = SHARED / "conformance"
pytestmark = pytest.mark.skipif(not CONF.is_dir(), reason=f"{CONF} not present: conformance cases skipped")

# (item, subfield in the independent decoder's naming) -> our column, per category
MAP = {
    48: {("I010", "SAC"): "sac", ("I010", "SIC"): "sic", ("I140", "ToD"): "time_of_day",
         ("I020", "TYP"): "typ", ("I020", "SIM"): "sim", ("I020", "RDP"): "rdp", ("I020", "SPI"): "spi",
         ("I020", "RAB"): "rab", ("I040", "RHO"): "rho_nm", ("I040", "THETA"): "theta_deg",
         ("I070", "V"): "mode3a_v", ("I070", "G"): "mode3a_g", ("I070", "L"): "mode3a_l",
         ("I070", "Mode3A"): "mode3a", ("I090", "V"): "flight_level_v", ("I090", "G"): "flight_level_g",
         ("I090", "FL"): "flight_level", ("I220", "ACAddr"): "address", ("I240", "TId"): "callsign",
         ("I161", "Tn"): "track_number", ("I200", "CGS"): "ground_speed_kt", ("I200", "CHdg"): "heading_deg",
         ("I170", "CNF"): "cnf", ("I170", "RAD"): "rad", ("I170", "DOU"): "dou", ("I170", "MAH"): "mah",
         ("I170", "CDM"): "cdm", ("I170", "TRE"): "tre", ("I170", "GHO"): "gho", ("I170", "SUP"): "sup",
         ("I170", "TCC"): "tcc", ("I230", "COM"): "com", ("I230", "STAT"): "flight_status"},
    21: {("I010", "SAC"): "sac", ("I010", "SIC"): "sic", ("I040", "ATP"): "atp", ("I040", "ARC"): "arc",
         ("I040", "RC"): "rc", ("I040", "RAB"): "rab", ("I040", "DCR"): "dcr", ("I040", "GBS"): "gbs",
         ("I040", "SIM"): "sim", ("I040", "TST"): "tst", ("I040", "SAA"): "saa", ("I040", "CL"): "cl",
         ("I161", "TrackN"): "track_number", ("I015", "id"): "service_id", ("I130", "Lat"): "latitude",
         ("I130", "Lon"): "longitude", ("I080", "TAddr"): "address",
         ("I073", "time_reception_position"): "time_reception_position",
         ("I075", "time_reception_velocity"): "time_reception_velocity",
         ("I077", "time_report_transmission"): "time_report_transmission",
         ("I140", "geometric_height"): "geometric_height_ft", ("I090", "NUCr_or_NACv"): "nucr_nacv",
         ("I090", "NUCp_or_NIC"): "nucp_nic", ("I210", "VN"): "mops_version",
         ("I210", "LTT"): "link_technology", ("I070", "Mode3A"): "mode3a", ("I145", "FL"): "flight_level",
         ("I170", "TId"): "callsign", ("I020", "ECAT"): "emitter_category",
         ("I200", "ICF"): "icf", ("I200", "LNAV"): "lnav_not_engaged", ("I200", "PS"): "priority_status",
         ("I200", "SS"): "surveillance_status"},
}


def _cases():
    if not CONF.is_dir():
        return []
    return sorted(p for p in CONF.iterdir() if not p.name.endswith((".json", ".md")))


@pytest.mark.parametrize("path", _cases(), ids=lambda p: p.name)
def test_conformance_file(path):
    expected = json.loads(path.with_name(path.name + ".expected.json").read_text())
    rec = asterix.read(path, editions={21: "2.1"})
    assert rec.errors.empty, rec.errors.to_dict("records")
    cats = [e["category"] for e in expected]
    frames = {c: rec.frames[c].reset_index(drop=True) for c in set(cats)}
    seen = {c: 0 for c in set(cats)}
    compared = 0
    for exp in expected:
        cat = exp["category"]
        row = frames[cat].iloc[seen[cat]]
        seen[cat] += 1
        for item, fields in exp.items():
            if item == "category" or not isinstance(fields, dict):
                continue
            for name, value in fields.items():
                col = MAP[cat].get((item, name))
                if col is None:
                    continue
                got = row[col]
                if isinstance(value, str):
                    assert str(got) == value.rstrip(), (item, name)
                else:
                    assert not pd.isna(got), (item, name)
                    assert math.isclose(float(got), float(value), rel_tol=1e-9, abs_tol=1e-9), (item, name)
                compared += 1
    assert all(len(frames[c]) == seen[c] for c in frames)
    assert compared >= 10 * len(expected)
