"""The polar PD map and the vertical coverage diagram: each cell drawn as its grid says (a value where there
are enough expected updates, grey where too few, nothing where none), written as PNG."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import QuadMesh

from msdc.pipeline.report.coverage_figures import (
    coverage_images,
    grid_arrays,
    polar_pd_figure,
    polar_pd_map,
    vertical_coverage,
    vertical_coverage_figure,
)

# 2 range bands x 3 sectors, x varying slowest: (0-10, 0-120) 18 of 20; (0-10, 120-240) 3 of 5, too few;
# (0-10, 240-360) none expected; (10-20, 0-120) 0 of 40; (10-20, 120-240) 30 of 30; (10-20, 240-360) 1 of 1
GRID = pd.DataFrame({
    "x_low": [0.0, 0, 0, 10, 10, 10], "x_high": [10.0, 10, 10, 20, 20, 20],
    "y_low": [0.0, 120, 240, 0, 120, 240], "y_high": [120.0, 240, 360, 120, 240, 360],
    "expected": [20, 5, 0, 40, 30, 1], "detected": [18, 3, 0, 0, 30, 1],
    "pd": [0.9, 0.6, np.nan, 0.0, 1.0, 1.0], "enough": [True, False, False, True, True, False]})
VALUES = [[0.9, np.nan, np.nan], [0.0, 1.0, np.nan]]
FEW = [[False, True, False], [False, False, True]]


def test_grid_arrays_place_each_cell():
    xe, ye, value, few = grid_arrays(GRID)
    assert xe.tolist() == [0, 10, 20] and ye.tolist() == [0, 120, 240, 360]
    np.testing.assert_array_equal(value, VALUES)
    assert few.tolist() == FEW
    shuffled = grid_arrays(GRID.sample(frac=1.0, random_state=1))
    np.testing.assert_array_equal(shuffled[2], VALUES)


def _meshes(fig) -> list[np.ma.MaskedArray]:
    (ax,) = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    return [c.get_array() for c in ax.collections if isinstance(c, QuadMesh)]


@pytest.mark.parametrize("draw", [polar_pd_map, vertical_coverage])
def test_values_only_where_enough_and_grey_where_too_few(draw):
    values, grey = _meshes(draw(GRID, min_expected=20))
    shown = values.reshape(2, 3) if draw is polar_pd_map else values.reshape(3, 2).T
    grey = grey.reshape(2, 3) if draw is polar_pd_map else grey.reshape(3, 2).T
    assert (~np.ma.getmaskarray(shown)).tolist() == [[True, False, False], [True, True, False]]
    assert shown.compressed().tolist() == [0.9, 0.0, 1.0]
    assert (~np.ma.getmaskarray(grey)).tolist() == FEW


def test_figures_are_written(tmp_path):
    polar = polar_pd_figure(GRID, tmp_path / "maps" / "polar.png", "radar", min_expected=20)
    vertical = vertical_coverage_figure(GRID.assign(y_low=GRID["y_low"] * 100, y_high=GRID["y_high"] * 100),
                                        tmp_path / "vertical.png", cone_elevation_deg=40.0,
                                        max_range_nm=15.0)
    for path in (polar, vertical):
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_grid_without_its_columns_is_refused():
    with pytest.raises(ValueError, match="missing enough"):
        grid_arrays(GRID.drop(columns="enough"))


def _png_size(data: bytes) -> tuple[int, int]:
    """Width and height from a PNG's IHDR chunk (PNG specification 11.2.2: bytes 16-23, big-endian)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_coverage_images_are_pngs_keyed_by_title():
    vertical = GRID.assign(y_low=GRID["y_low"] * 100, y_high=GRID["y_high"] * 100)
    images = coverage_images(GRID, vertical, "SSR1", min_expected=20, cone_elevation_deg=40.0)
    assert list(images) == ["SSR1: probability of detection by range and azimuth",
                            "SSR1: vertical coverage (probability of detection by range and height)"]
    # the figures are 7.5 x 7.5 in and 10 x 5.5 in at 130 dots per inch
    assert [_png_size(b) for b in images.values()] == [(975, 975), (1300, 715)]
    assert coverage_images(None, GRID.iloc[:0], "SSR1") == {}
    assert list(coverage_images(GRID, None, "x")) == ["x: probability of detection by range and azimuth"]
