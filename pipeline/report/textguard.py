"""Formula-injection guard for text written to CSV files (OWASP "CSV injection").

A spreadsheet opening a CSV runs a cell that begins with ``= + - @`` (or a tab or carriage return) as a
formula. Such text is written with a leading apostrophe, which spreadsheets show as plain text. Only
text columns are touched; numbers stay numbers.
"""

from __future__ import annotations

import pandas as pd

FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def is_formula_like(text: str) -> bool:
    """True when a spreadsheet would read ``text`` as a formula."""
    return text.startswith(FORMULA_START)


def neutralise(value: object) -> object:
    """``value`` with an apostrophe in front when it is formula-like text; anything else unchanged."""
    return "'" + value if isinstance(value, str) and is_formula_like(value) else value


def guard_frame(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with its text columns (object, string, categorical) neutralised; the other columns are not
    copied."""
    out = {}
    for name in frame.columns:
        column = frame[name]
        kind = column.dtype
        if isinstance(kind, pd.CategoricalDtype):
            categories = [neutralise(c) for c in kind.categories]
            if categories != list(kind.categories):
                try:
                    column = column.cat.rename_categories(categories)
                except ValueError:  # "=x" and "'=x" both present: give up the categorical
                    column = column.astype(object).map(neutralise, na_action="ignore")
        elif pd.api.types.is_object_dtype(kind) or isinstance(kind, pd.StringDtype):
            if not _any_formula_like(column):
                continue  # as it is (the common case: each distinct value looked at once, not every cell)
            column = column.map(neutralise, na_action="ignore")
        else:
            continue
        out[name] = column
    guarded = frame.copy(deep=False)
    for name, column in out.items():
        guarded[name] = column
    return guarded


def _any_formula_like(column: pd.Series) -> bool:
    """Whether any value of a text column is formula-like, each distinct value tested once (values that
    cannot be hashed: every one)."""
    try:
        values = pd.unique(column.to_numpy(object, na_value=None))
    except TypeError:
        values = column.to_numpy(object)
    return any(isinstance(v, str) and is_formula_like(v) for v in values)
