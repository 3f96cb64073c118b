"""Turn the kernel's column arrays into typed pandas columns (nullable ints, text, floats)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from .columns import Column

_ICAO = np.array(["?"] * 64)
_ICAO[1:27] = list("ABCDEFGHIJKLMNOPQRSTUVWXYZ")
_ICAO[32] = " "
_ICAO[48:58] = list("0123456789")


_ALL_SPACES = int("100000" * 8, 2)


def icao_text(raw: int) -> str:
    """The 8-character ICAO 6-bit string of a 48-bit value, trailing spaces stripped; "" (absent) for
    all-zero codes (code 0 is no character) or all spaces. A code outside A-Z, space, 0-9 shows as '?'
    (never a letter); the raw value stays in the ``*_hex`` column."""
    if raw == 0 or raw == _ALL_SPACES:
        return ""
    return "".join(_ICAO[(raw >> (42 - 6 * i)) & 63] for i in range(8)).rstrip()


def _text_column(raw: np.ndarray, fmt, factorized=None) -> pd.Categorical:
    """Categorical text from raw ints (-1 = absent): each distinct value is formatted once."""
    codes, uniques = factorized if factorized is not None else pd.factorize(raw, sort=False)
    labels = [fmt(int(u)) for u in uniques]
    missing = [i for i, u in enumerate(uniques) if u < 0 or labels[i] == ""]
    if missing:
        remap = np.arange(len(uniques))
        keep = np.ones(len(uniques), bool)
        keep[missing] = False
        remap[keep] = np.arange(keep.sum())
        remap[~keep] = -1
        codes = np.where(codes >= 0, remap[codes], -1)
        labels = [lab for i, lab in enumerate(labels) if keep[i]]
    # identical labels from distinct raws (e.g. trailing-space variants) are merged
    cats, inv = np.unique(np.array(labels, dtype=object), return_inverse=True) if labels else ([], [])
    if len(labels):
        codes = np.where(codes >= 0, np.asarray(inv)[np.maximum(codes, 0)], -1)
    return pd.Categorical.from_codes(codes, categories=pd.Index(list(cats), dtype=object))


_FORMATS = {
    "hex": lambda v: f"{v:06X}",
    "hex48": lambda v: f"{v:012X}",
    "octal": lambda v: f"{v:04o}",
    "icao": icao_text,
}
_INT_DTYPES = {"flag": np.int8, "int": np.int32, "count": np.int16, "bdsflag": np.int8, "bdsint": np.int16}


def typed_column(col: Column, values: np.ndarray):
    """One pandas column from kernel output (floats with NaN, or ints with -1 for absent)."""
    if col.kind == "float":
        return values
    if col.kind in _FORMATS:
        return _text_column(values, _FORMATS[col.kind])
    dtype = _INT_DTYPES[col.kind]  # flags come as int8 and ints as int32 rows: kept, not copied
    return pd.arrays.IntegerArray(values.astype(dtype, copy=False), values < 0)


def icao_columns(values: np.ndarray) -> tuple[pd.Categorical, pd.Categorical]:
    """Identification text and its raw 48 bits as 12 hex digits (<NA> when absent), factorized once."""
    factorized = pd.factorize(values, sort=False)
    return _text_column(values, icao_text, factorized), _text_column(values, _FORMATS["hex48"], factorized)


def empty_column(col: Column, n: int):
    """An all-absent column of the right dtype, for fields the edition does not have."""
    if col.kind in ("float", "bds"):
        return np.full(n, np.nan)
    if col.kind in ("codes", "bdstext"):
        return pd.Categorical.from_codes(np.full(n, -1), categories=pd.Index([], dtype=object))
    return typed_column(col, np.full(n, -1, np.int64))


def empty_columns(cols: list[Column], n: int) -> dict[str, object]:
    """All-absent columns (``empty_column``'s) for several columns at once: one array per dtype, the same
    object for every column of that dtype (a wide edition's absent columns cost one column's memory and
    fill, not one each; ``frame_of`` makes the frame's columns copy on write), text ones one empty
    categorical; an ``icao`` column with its ``_hex`` beside it."""
    out: dict[str, object] = {}
    floats = [c for c in cols if c.kind in ("float", "bds")]
    ints = [c for c in cols if c.kind in _INT_DTYPES]
    if floats:
        nan = np.full(n, np.nan)
        out |= {c.name: nan for c in floats}
    for dtype in {_INT_DTYPES[c.kind] for c in ints}:
        absent = pd.arrays.IntegerArray(np.zeros(n, dtype), np.ones(n, bool))
        out |= {c.name: absent for c in ints if _INT_DTYPES[c.kind] == dtype}
    texts = [c for c in cols if c.name not in out]
    if texts:  # categorical codes -1
        none = pd.Categorical.from_codes(np.full(n, -1, np.int8), categories=pd.Index([], dtype=object))
        for c in texts:
            out[c.name] = none
            if c.kind == "icao":
                out[f"{c.name}_hex"] = none
    return out


def frame_of(cols: dict[str, object]) -> pd.DataFrame:
    """A DataFrame of these columns without copying them; an array given for several columns (the absent
    ones: ``empty_columns``) goes in as views whose writes copy first (pandas' copy on write), so that
    setting a value in one column never shows in another."""
    uses: dict[int, int] = {}
    for v in cols.values():
        uses[id(v)] = uses.get(id(v), 0) + 1
    shared: dict[int, pd.Series] = {}
    data = {}
    for name, v in cols.items():
        if uses[id(v)] > 1:
            base = shared.setdefault(id(v), pd.Series(v, copy=False))
            data[name] = base.copy(deep=False)
        else:
            data[name] = v
    return pd.DataFrame(data, copy=False)


def code_list_column(buf: np.ndarray, rec_off: np.ndarray, rel_off: np.ndarray, rel_len: np.ndarray
                     ) -> pd.Categorical:
    """Text of an FX-repetitive item of one-byte repetitions (7-bit code, FX): its codes in wire order
    joined by ',' ('3', '1,3'); <NA> where the record lacks the item. Each distinct item is read once."""
    n = rec_off.shape[0]
    codes = np.full(n, -1, np.int64)
    present = np.flatnonzero(rel_len != 0)
    labels: list[str] = []
    if len(present):
        lens = rel_len[present].astype(np.int64)
        width = int(lens.max())
        cols = np.arange(width)
        inside = cols[None, :] < lens[:, None]
        at = (rec_off[present] + rel_off[present].astype(np.int64))[:, None] + cols[None, :]
        mat = np.zeros((len(present), max(width, 8)), np.uint8)
        mat[:, :width] = np.where(inside, buf[np.where(inside, at, 0)], 0)
        if width <= 8:  # up to 8 codes (nearly always): each item as one integer, hashed
            inverse, uniq = pd.factorize(mat.view(">u8").ravel().astype(np.uint64))
            labels = [_code_text(int(u).to_bytes(8, "big")) for u in uniq]
        else:
            rows = mat.view(np.dtype((np.void, mat.shape[1]))).ravel()
            uniq, inverse = np.unique(rows, return_inverse=True)
            labels = [_code_text(bytes(u)) for u in uniq]
        codes[present] = np.asarray(inverse).ravel()
    return pd.Categorical.from_codes(codes, categories=pd.Index(labels, dtype=object))


def _code_text(item: bytes) -> str:
    """'3,12' from the bytes of one item (each 7-bit code then FX; bytes after the last FX=0 are padding)."""
    out = []
    for b in item:
        out.append(str(b >> 1))
        if not b & 1:
            break
    return ",".join(out)
