"""The conflict alert figure's PC panel: gaps drawn as gaps, the time range fitted to the pair's samples."""

import numpy as np
import pandas as pd

from pipeline.report.conflict_figures import pc_line, pc_window

T0 = pd.Timestamp("2016-05-10 22:04:25", tz="UTC")


def at(*seconds):
    return pd.Series([T0 + pd.Timedelta(seconds=s) for s in seconds])


def test_pc_line_breaks_where_a_sample_is_missing():
    # samples at 0, 5, 10 s, then 100 s and 195-200 s (the 120 s horizon of 344548/4CA5F7 on the real
    # ADS-B recording: the predicted levels 975 ft or more apart in between, so no PC there)
    t, v = pc_line(at(0, 5, 10, 100, 195, 200), [0.1, 0.2, 0.3, 0.34, 0.24, 0.21], 5.0)
    assert np.isnan(v).tolist() == [False, False, False, True, False, True, False, False]
    assert np.isnat(t).tolist() == np.isnan(v).tolist()
    assert v[~np.isnan(v)].tolist() == [0.1, 0.2, 0.3, 0.34, 0.24, 0.21]
    assert len(pc_line(at(0, 5, 10), [0.5] * 3, 5.0)[1]) == 3  # no gap: nothing added


def test_pc_window_fits_the_samples_not_the_whole_map_window():
    alert = pd.Series({"start": T0 + pd.Timedelta(seconds=80), "end": T0 + pd.Timedelta(seconds=85),
                       "loss_start": T0 + pd.Timedelta(seconds=80)})
    t0, t1 = T0 - pd.Timedelta(seconds=40), T0 + pd.Timedelta(seconds=205)  # 120 s before, 120 s after
    lo, hi = pc_window(at(80, 85), alert, 5.0, t0, t1)
    assert (lo, hi) == (T0 + pd.Timedelta(seconds=75), T0 + pd.Timedelta(seconds=90))  # a step either side
    lo, hi = pc_window(at(0, 200), alert, 5.0, t0, t1)  # 200 s of samples: 10 s (5 %) either side, clipped
    assert (lo, hi) == (T0 - pd.Timedelta(seconds=10), t1)
