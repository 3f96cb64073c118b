"""The category registry agrees with the edition tables shipped in asterix/tables."""

from pathlib import Path

import pytest

from msdc.asterix.categories import DECODABLE, MEASUREMENT_CATEGORIES, REGISTRY, category

TABLES = Path(__file__).resolve().parents[2] / "asterix" / "tables"
SHIPPED: dict[int, set[str]] = {}
for _p in TABLES.glob("cat*_*.json"):
    _cat, _ed = _p.stem[3:].split("_")
    SHIPPED.setdefault(int(_cat), set()).add(_ed)


def test_every_shipped_category_is_registered_and_every_registered_one_is_shipped():
    assert set(REGISTRY) == set(SHIPPED) == set(DECODABLE)


@pytest.mark.parametrize("number", sorted(REGISTRY))
def test_default_edition_and_aliases_name_shipped_tables(number):
    entry = REGISTRY[number]
    assert entry.default_edition in SHIPPED[number]
    assert set(entry.aliases.values()) <= SHIPPED[number]
    assert not set(entry.aliases) & SHIPPED[number]  # an alias never hides a table of its own


def test_measurement_categories_are_radar_then_adsb_then_surface_and_multilateration():
    assert MEASUREMENT_CATEGORIES == (48, 21, 10, 20)
    assert REGISTRY[48].label == "CAT048" and REGISTRY[21].noun == "ADS-B"
    assert REGISTRY[10].label == "CAT010" and REGISTRY[20].noun == "multilateration"


def test_an_unknown_category_is_named_with_the_known_ones():
    known = "CAT048, CAT021, CAT010, CAT020, CAT034, .*CAT001, CAT002.*CAT062"
    with pytest.raises(KeyError, match=f"CAT008 is not decoded by msdc .*{known}"):
        category(8)


@pytest.mark.parametrize("number", [62, 19, 23, 25, 63, 65])
def test_tracks_and_status_categories_are_decoded_only_when_asked(number):
    assert number in DECODABLE and number not in MEASUREMENT_CATEGORIES
