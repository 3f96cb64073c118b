"""A span's tables of expected and detected updates (detection bands, the polar and vertical PD grids)
folded window by window as sums per key, made a table once at the end: the table combining every window's
tables at once gives (evaluate.windows.combine_counts and combine_grid, their key order, columns and
dtypes), without a concatenation, a group-by and merges per window in the main process."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.statistics import proportion

GRID_KEYS = ["x_low", "x_high", "y_low", "y_high"]
_COUNTS = ("expected", "detected")
_RATES = ("pd", "ci_low", "ci_high")


class CountFold:
    """Expected and detected updates per key (``keys``: a band's low and high, a class, or a grid's cell
    when ``grid``) summed over the tables added; ``table()`` is what combining them all gives."""

    def __init__(self, keys: list[str], grid: bool = False) -> None:
        self.keys, self.grid = list(keys), grid
        self.sums: dict[tuple, list] = {}  # key -> [expected, detected], in order of first appearance
        self.columns: list[str] = []  # every table's columns, in order of first appearance
        self.dtypes: dict[str, object] = {}  # each key column's dtype, and the counts' (as pandas adds them)

    def add(self, table: pd.DataFrame | None) -> None:
        """Fold one window's table in (None or empty: nothing)."""
        if table is None or not len(table):
            return
        self.columns += [c for c in table.columns if c not in self.columns]
        for c in (*self.keys, *_COUNTS):
            dtype = table[c].dtype
            self.dtypes[c] = dtype if c not in self.dtypes else _common(self.dtypes[c], dtype)
        keys = zip(*(table[c].tolist() for c in self.keys), strict=True)
        sums = self.sums
        for key, e, d in zip(keys, table["expected"].tolist(), table["detected"].tolist(), strict=True):
            held = sums.get(key)
            if held is None:
                sums[key] = [e, d]
            else:
                held[0] += e
                held[1] += d

    def table(self) -> pd.DataFrame:
        """The folded table with PD and its Clopper-Pearson interval (and ``enough`` where the tables had
        it): bands by their lower end, classes as first seen, a grid's cells on the whole rectangle of its
        bands (x, then y, ascending; a cell no window reached: nothing expected)."""
        from msdc.pipeline.evaluate.bins import MIN_EXPECTED

        if not self.sums:
            return pd.DataFrame()
        if self.grid:
            return self._grid(MIN_EXPECTED)
        keys = list(self.sums)
        if self.keys == ["low", "high"]:
            keys.sort(key=lambda k: k[0])
        out = pd.DataFrame({c: pd.array([k[i] for k in keys], dtype=self.dtypes[c])
                            for i, c in enumerate(self.keys)})
        for i, c in enumerate(_COUNTS):
            out[c] = np.array([self.sums[k][i] for k in keys], dtype=self.dtypes[c])
        return self._finished(out, self.columns, MIN_EXPECTED)

    def _grid(self, min_expected: int) -> pd.DataFrame:
        """The folded cells on the rectangle their x and y bands make, x varying slowest."""
        xs = sorted(dict.fromkeys((k[0], k[1]) for k in self.sums), key=lambda b: b[0])
        ys = sorted(dict.fromkeys((k[2], k[3]) for k in self.sums), key=lambda b: b[0])
        cells = [(x[0], x[1], y[0], y[1]) for x in xs for y in ys]
        out = pd.DataFrame({c: pd.array([k[i] for k in cells], dtype=self.dtypes[c])
                            for i, c in enumerate(GRID_KEYS)})
        zero = [0, 0]
        for i, c in enumerate(_COUNTS):
            dtype = _common(np.dtype(np.int64), self.dtypes[c])  # the rectangle's empty cells count 0
            out[c] = np.array([self.sums.get(k, zero)[i] for k in cells], dtype=dtype)
        return self._finished(out, [*GRID_KEYS, *_COUNTS, *self.columns], min_expected)

    def _finished(self, out: pd.DataFrame, columns: list[str], min_expected: int) -> pd.DataFrame:
        """PD, interval and ``enough`` added, the columns in the combination's order."""
        p = proportion(out["detected"].to_numpy(np.int64), out["expected"].to_numpy(np.int64))
        out["pd"], out["ci_low"], out["ci_high"] = p.value, p.ci_low, p.ci_high
        if "enough" in self.columns:
            out["enough"] = out["expected"].to_numpy() >= min_expected
        order = list(dict.fromkeys(c for c in columns if c in out.columns))
        return out[[*order, *(c for c in _RATES if c not in order)]]


def _common(a, b):
    """The dtype pandas gives a column of both (numpy's promotion for numbers; object otherwise)."""
    try:
        return np.result_type(a, b)
    except TypeError:
        return a if a == b else np.dtype(object)
