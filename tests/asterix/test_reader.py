"""The Recording read returns: compared by identity, indexed by category with a KeyError that says what it
holds (expected texts written from the fixtures' contents: radar.ast holds CAT048 only, adsb.ast CAT021)."""

from __future__ import annotations

from pathlib import Path

import pytest

import msdc.asterix as asterix

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"
RADAR, ADSB = FIXTURES / "radar.ast", FIXTURES / "adsb.ast"


def test_recordings_compare_by_identity():
    """read(P) == read(P) raised 'The truth value of a DataFrame is ambiguous' (the dataclass compared its
    frames); a Recording is equal to itself only, and can be a set member or a dict key."""
    one, two = asterix.read(RADAR), asterix.read(RADAR)
    assert one == one and one != two and not (one == two)
    assert len({one, two, one}) == 2


def test_a_category_not_held_names_the_ones_held(tmp_path):
    """read(radar)[21] raised a bare KeyError: 21."""
    rec = asterix.read(RADAR)
    assert rec[48] is rec.frames[48]
    with pytest.raises(KeyError, match=r"^'21: no frame of this category \(the recording holds none\); "
                                       r"frames: CAT048'$"):
        rec[21]
    with pytest.raises(KeyError, match=r"'48': no frame of this category \(a category is a number"):
        rec["48"]
    both = tmp_path / "both.ast"  # two raw streams laid end to end are one: CAT048 blocks, then CAT021
    both.write_bytes(RADAR.read_bytes() + ADSB.read_bytes())
    rec = asterix.read(both, categories=48)
    with pytest.raises(KeyError, match=r"^'21: no frame of this category \(its blocks were not decoded "
                                       r"\(give categories=\)\); frames: CAT048'$"):
        rec[21]
