"""asterix.layout.column_resolution: a column's step, read from the item tables (values from the specs)."""

from __future__ import annotations

import pytest

from msdc.asterix.layout import column_resolution
from msdc.asterix.tables import available


@pytest.mark.parametrize("category, column, step", [
    (10, "x_m", 1.0),  # I010/042: LSB 1 m
    (20, "x_m", 0.5),  # I020/042: LSB 0.5 m
    (10, "latitude", 180.0 / 2**31),  # I010/041
    (20, "latitude", 180.0 / 2**25),  # I020/041
    (48, "x_nm", 1.0 / 128),  # I048/042: 1/128 NM
    (48, "rho_nm", 1.0 / 256),  # I048/040: 1/256 NM
])
def test_every_edition_gives_the_specified_step(category, column, step):
    for edition in available()[category]:
        assert column_resolution(category, column, edition) == (pytest.approx(step, rel=1e-12),), edition


def test_a_column_read_from_two_items_gives_both_steps_in_the_order_tried():
    # CAT021 2.x latitude: I021/131 (180/2^30 deg) first, else I021/130 (180/2^23 deg); 0.23 has only one
    want = (180.0 / 2**30, 180.0 / 2**23)
    assert column_resolution(21, "latitude", "2.1") == pytest.approx(want, rel=1e-12)
    assert column_resolution(21, "latitude", "0.23") == pytest.approx((180.0 / 2**23,), rel=1e-12)


def test_a_column_the_edition_lacks_or_not_a_quantity_has_no_step():
    assert column_resolution(10, "x_nm") == ()
    assert column_resolution(21, "callsign", "2.1") == ()
