"""ASTERIX encoder: engineering values -> item bytes, records and data blocks (the decoder's inverse).

Items are laid out from the edition tables (``asterix/tables/*.json``); records and frames are keyed by the
column names of ``asterix/columns/`` so that encode -> decode gives back the same values.
"""

from __future__ import annotations

import math
import string
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
import pandas as pd
from bitstring import BitArray, Bits, pack

from msdc.asterix.columns import BDS_KINDS, Column, columns_for
from msdc.asterix.frames import icao_text
from msdc.asterix.tables import available, load_table, resolve_edition, uaps

__all__ = [
    "EDITIONS", "load_table", "encode_item", "encode_record", "encode_block", "encode_frame", "item_fields",
]

EDITIONS: dict[int, list[str]] = available()
MAX_BLOCK = 0xFFFF
_ICAO_CODE = {**{chr(64 + i): i for i in range(1, 27)}, " ": 32, **{str(d): 48 + d for d in range(10)}}
_CHUNK = 1 << 16  # rows encoded at once by encode_frame (bounds the padded byte matrices)


# ---------------------------------------------------------------------------------------------------------
# Layouts: one per (category, edition, item), compiled once from the table nodes.


@dataclass(frozen=True)
class Field:
    """One element: its path in the item, bit offset in its fixed part (MSB first), width and content."""

    path: str
    offset: int
    bits: int
    type: str  # raw | table | quantity | integer | string
    signed: bool = False
    lsb: float = 1.0
    string: str = ""  # ICAO | Octal for strings

    @property
    def lo(self) -> int:
        """Smallest raw value the field holds."""
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def hi(self) -> int:
        """Largest raw value the field holds."""
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1


@dataclass(frozen=True)
class Fixed:
    """A fixed-size run of elements and spares (an element, a group, an octet group without its FX)."""

    bits: int
    segments: tuple[Field | int, ...]  # fields, and spare widths as ints
    fields: dict[str, Field]
    fmt: str  # bitstring pack format: one 'u<bits>' per segment


@dataclass(frozen=True)
class Extended:
    """Octet groups, each but possibly the last followed by an FX bit."""

    groups: tuple[Fixed, ...]
    fx: tuple[bool, ...]


@dataclass(frozen=True)
class Repetitive:
    """N copies of a fixed element: after a count byte (rep_bytes 1) or each followed by an FX bit."""

    path: str  # the path a count column addresses
    rep_bytes: int | None
    inner: Fixed  # paths relative to one repetition


@dataclass(frozen=True)
class Compound:
    """Subitems announced by their own FSPEC (7 presence bits per octet + FX)."""

    subs: tuple[tuple[str, Any] | None, ...]
    aliases: dict[str, str]  # "SRL" -> "SRL/SRL" for subitems that are a bare element


@dataclass(frozen=True)
class Explicit:
    """A length byte counting itself, then opaque content (RE, SP)."""


Layout = Fixed | Extended | Repetitive | Compound | Explicit


@dataclass(frozen=True)
class Item:
    """A UAP entry with its compiled layout."""

    frn: int
    id: str
    layout: Layout


def _fixed(nodes: Iterable[dict], prefix: tuple[str, ...]) -> Fixed:
    segments: list[Field | int] = []
    offset = 0

    def walk(node: dict, path: tuple[str, ...]) -> None:
        nonlocal offset
        if node.get("name"):
            path = (*path, node["name"])
        kind = node["kind"]
        if kind == "spare":
            segments.append(node["bits"])
            offset += node["bits"]
        elif kind == "element":
            segments.append(Field("/".join(path), offset, node["bits"], node.get("type", "raw"),
                                  bool(node.get("signed", False)), float(node.get("lsb", 1.0)),
                                  node.get("string", "")))
            offset += node["bits"]
        elif kind == "group":
            for child in node["items"]:
                walk(child, path)
        else:
            raise ValueError(f"{kind} node inside a fixed-size part at {'/'.join(path)!r}")

    for node in nodes:
        walk(node, prefix)
    fields = {s.path: s for s in segments if isinstance(s, Field)}
    if len(fields) != sum(isinstance(s, Field) for s in segments):
        raise ValueError(f"duplicate field paths under {'/'.join(prefix)!r}")
    fmt = ", ".join(f"u{s.bits if isinstance(s, Field) else s}" for s in segments)
    return Fixed(offset, tuple(segments), fields, fmt)


def _layout(node: dict, prefix: tuple[str, ...]) -> Layout:
    kind = node["kind"]
    if kind in ("element", "group", "spare"):
        return _fixed([node], prefix)
    if kind == "extended":
        groups = tuple(_fixed(g, prefix) for g in node["groups"])
        fx = tuple(bool(f) for f in node["fx"])  # from the table: I021/271 in 2.1 ends without FX
        for i, g in enumerate(groups):
            if (g.bits + fx[i]) % 8 or (not fx[i] and i != len(groups) - 1):
                raise ValueError(f"extended octet group {i} of {g.bits} bits at {'/'.join(prefix)!r}")
        return Extended(groups, fx)
    if kind == "repetitive":
        inner = _fixed([node["item"]], ())
        if node["rep_bytes"] is None and inner.bits % 8 != 7 or node["rep_bytes"] and inner.bits % 8:
            raise ValueError(f"repetitive element of {inner.bits} bits at {'/'.join(prefix)!r}")
        return Repetitive("/".join(prefix), node["rep_bytes"], inner)
    if kind == "compound":
        subs: list[tuple[str, Any] | None] = []
        aliases: dict[str, str] = {}
        for sub in node["subitems"]:
            if sub is None:
                subs.append(None)
                continue
            child = sub["node"]
            if child["kind"] == "element" and not child.get("name"):
                child = {**child, "name": sub["name"]}  # a bare element subitem is named like the subitem
                aliases[sub["name"]] = f"{sub['name']}/{sub['name']}"
            subs.append((sub["name"], _layout(child, (*prefix, sub["name"]))))
        return Compound(tuple(subs), aliases)
    if kind == "explicit":
        return Explicit()
    raise ValueError(f"unknown node kind {kind!r}")


@cache
def _uap_items(category: int, edition: str) -> dict[str, dict[str, Item]]:
    """The items of each UAP of an edition (resolved name; "" for a category with one UAP), compiled, by
    item id. RFS (Random Field Sequencing) is not encoded: the decoder does not walk it either."""
    out: dict[str, dict[str, Item]] = {}
    for name, uap in uaps(load_table(category, edition)).items():
        out[name] = {e["id"]: Item(frn, e["id"], _layout(e["node"], ()))
                     for frn, e in enumerate(uap, start=1) if e is not None and e["node"]["kind"] != "rfs"}
    return out


@cache
def _items(category: int, edition: str) -> dict[str, Item]:
    """All items of an edition by item id, of every UAP (an item in several: its first UAP's FRN)."""
    out: dict[str, Item] = {}
    for items in _uap_items(category, edition).values():
        for item_id, item in items.items():
            out.setdefault(item_id, item)
    return out


@dataclass(frozen=True)
class _Selector:
    """The field whose value chooses a record's UAP (CAT001 I001/020 TYP), and the UAP of each value."""

    item: str
    path: str
    field: Field  # in the item's first octet-group
    uap: dict[int, str]
    column: str  # the column that writes it ("typ")


@cache
def _selector(category: int, edition: str) -> _Selector | None:
    """The UAP selector of an edition with several UAPs, None with one."""
    sel = load_table(category, edition).get("selector")
    if sel is None:
        return None
    path = "/".join(sel["field"])
    layout = _items(category, edition)[sel["item"]].layout
    first = layout.groups[0] if isinstance(layout, Extended) else layout
    if not isinstance(first, Fixed) or path not in first.fields:
        raise ValueError(f"CAT{category:03d} {edition}: UAP selector {path!r} not in the first octets")
    column = next((c.name for c in columns_for(category, edition) if (sel["item"], tuple(sel["field"]))
                   in c.sources), f"I{category:03d}/{sel['item']} {path}")
    return _Selector(sel["item"], path, first.fields[path], {int(v): u for v, u in sel["values"].items()},
                     column)


def _uap_of(category: int, edition: str, value: int | None, later: bool, where: str) -> str:
    """The UAP a record is laid out by: the selector's value names it (None: the selector item is absent,
    allowed only when no item after it is present, ``later`` False)."""
    sel = _selector(category, edition)
    if sel is None:
        return ""
    if value is None:
        if later:
            raise ValueError(f"{where}: CAT{category:03d} records choose their UAP "
                             f"({' or '.join(sel.uap.values())}) by I{category:03d}/{sel.item} {sel.path}: "
                             f"give {sel.column!r} with the other values")
        return next(iter(sel.uap.values()))
    if value not in sel.uap:
        raise ValueError(f"{where}: I{category:03d}/{sel.item} {sel.path} = {value} chooses no UAP")
    return sel.uap[value]


def _check_category(category: Any) -> int:
    """``category`` as an int the encoder has tables for; TypeError for another type, ValueError for a
    category without tables, each naming the categories it encodes."""
    encoded = ", ".join(str(c) for c in sorted(EDITIONS))
    if isinstance(category, bool) or not isinstance(category, int | np.integer):
        raise TypeError(f"category {category!r}: a category number (an int), not {type(category).__name__}; "
                        f"the encoder encodes categories {encoded}")
    if int(category) not in EDITIONS:
        raise ValueError(f"category {category!r}: no edition table to encode it with; the encoder encodes "
                         f"categories {encoded}")
    return int(category)


def _check_edition(category: int, edition: Any) -> str:
    """The table name of ``edition`` (None: the default); TypeError for one that is not text."""
    if edition is not None and not isinstance(edition, str):
        raise TypeError(f"edition {edition!r}: a {type(edition).__name__}; give it as text, as the tables "
                        f"name it ('1.30': a float cannot hold 1.30; CAT{category:03d} tables: "
                        f"{', '.join(EDITIONS[category])})")
    return resolve_edition(category, edition)


def _item(category: int, edition: str | None, item_id: str) -> Item:
    category = _check_category(category)
    ed = _check_edition(category, edition)
    items = _items(category, ed)
    key = item_id.removeprefix(f"I{category:03d}/").removeprefix("I")
    if key not in items:
        raise ValueError(f"CAT{category:03d} edition {ed} has no item {item_id!r}")
    return items[key]


def _paths(layout: Layout) -> dict[str, Field | Repetitive]:
    """Addressable paths of a layout: its fields, and the count of each repetitive part."""
    if isinstance(layout, Fixed):
        return dict(layout.fields)
    if isinstance(layout, Extended):
        return {p: f for g in layout.groups for p, f in g.fields.items()}
    if isinstance(layout, Repetitive):
        return {layout.path: layout}
    if isinstance(layout, Compound):
        return {p: f for sub in layout.subs if sub for p, f in _paths(sub[1]).items()}
    return {}


def item_fields(category: int, edition: str | None, item_id: str) -> list[str]:
    """The field paths encode_item accepts for an item (repetitive parts: the list's key)."""
    return list(_paths(_item(category, edition, item_id).layout))


# ---------------------------------------------------------------------------------------------------------
# Values -> raw field bits.


def _at(f: Field, where: str) -> str:
    return f"{where or 'field'} {f.path or '(element)'!r}"


def _range_error(f: Field, value: Any, raw: int, where: str) -> ValueError:
    return ValueError(f"{_at(f, where)}: {value!r} -> raw {raw} is outside "
                      f"{f.bits}-bit {'signed' if f.signed else 'unsigned'} range [{f.lo}, {f.hi}]")


def _icao(text: str, f: Field, where: str) -> int:
    n = f.bits // 6
    text = text.upper()
    if len(text) > n:
        raise ValueError(f"{_at(f, where)}: {text!r} is longer than {n} characters")
    raw = 0
    for ch in text.ljust(n):
        if ch not in _ICAO_CODE:
            raise ValueError(f"{_at(f, where)}: {ch!r} is not an ICAO character")
        raw = raw << 6 | _ICAO_CODE[ch]
    return raw


def _octal(text: str, f: Field, where: str) -> int:
    n = f.bits // 3
    text = text.strip()
    if not 0 < len(text) <= n or any(c not in "01234567" for c in text):
        raise ValueError(f"{_at(f, where)}: {text!r} is not a {n}-digit octal code")
    return int(text, 8)


def _raw(f: Field, value: Any, where: str = "") -> int:
    """One engineering value as the field's raw bits (two's complement for signed fields)."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, str) and f.type == "quantity":
        value = float(value)
    if isinstance(value, str) and f.type == "string":
        raw = _icao(value, f, where) if f.string == "ICAO" else _octal(value, f, where)
    elif isinstance(value, str):
        try:
            raw = int(value, 16)
        except ValueError:
            raise ValueError(f"{_at(f, where)}: {value!r} is not hex") from None
    elif isinstance(value, bytes | bytearray):
        if len(value) != (f.bits + 7) // 8:
            raise ValueError(f"{_at(f, where)}: {len(value)} bytes for {f.bits} bits")
        raw = int.from_bytes(value, "big")
    elif f.type == "quantity":
        x = float(value)
        if not math.isfinite(x):
            raise ValueError(f"{_at(f, where)}: {value!r} is not finite")
        raw = math.floor(x / f.lsb + 0.5)
    else:
        if isinstance(value, bool):
            value = int(value)
        if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
            raise ValueError(f"{_at(f, where)}: {value!r} is not an integer")
        raw = int(value)
    lo, hi = (f.lo, f.hi) if f.type in ("quantity", "integer") else (0, (1 << f.bits) - 1)
    if not lo <= raw <= hi:
        raise _range_error(f, value, raw, where)
    return raw & ((1 << f.bits) - 1)


# ---------------------------------------------------------------------------------------------------------
# encode_item: one item from a dict of field values, assembled with bitstring.


def _check_keys(keys: Iterable[str], known: Iterable[str], where: str) -> None:
    unknown = set(keys) - set(known)
    if unknown:
        raise ValueError(f"{where}: unknown field(s) {sorted(unknown)}; known: {sorted(known)}")


def _fixed_bits(fx: Fixed, fields: Mapping[str, Any], where: str) -> Bits:
    values = [0 if isinstance(s, int) else
              _raw(s, fields[s.path], where) if fields.get(s.path) is not None else 0 for s in fx.segments]
    return pack(fx.fmt, *values)


def _fspec_bits(present: list[bool]) -> Bits:
    last = max((i for i, p in enumerate(present) if p), default=-1)
    if last < 0:
        raise ValueError("nothing to encode: no item or subitem present")
    n = last // 7 + 1
    bits = BitArray()
    for octet in range(n):
        for k in range(7):
            i = octet * 7 + k
            bits.append(Bits.from_bools([i < len(present) and present[i]]))
        bits.append(Bits.from_bools([octet < n - 1]))
    return bits


def _repetitions(value: Any) -> list[Any]:
    if isinstance(value, Mapping):
        value = value.get("", [])
    if isinstance(value, bytes | bytearray | str) or not isinstance(value, Iterable):
        raise ValueError(f"repetitive item needs a list of repetitions, got {type(value).__name__}")
    return list(value)


def _one_repetition(inner: Fixed, rep: Any, where: str) -> Bits:
    if isinstance(rep, bytes | bytearray):
        if len(rep) * 8 != inner.bits:
            raise ValueError(f"{where}: repetition of {len(rep)} bytes, expected {inner.bits // 8}")
        return Bits.from_bytes(bytes(rep))
    if not isinstance(rep, Mapping):
        rep = {"": rep}
    _check_keys(rep, inner.fields, where)
    return _fixed_bits(inner, rep, where)


def _encode_bits(layout: Layout, fields: Any, where: str) -> Bits:
    if isinstance(layout, Fixed):
        if isinstance(fields, bytes | bytearray):
            if len(fields) * 8 != layout.bits:
                raise ValueError(f"{where}: {len(fields)} bytes given, item is {layout.bits // 8}")
            return Bits.from_bytes(bytes(fields))
        _check_keys(fields, layout.fields, where)
        return _fixed_bits(layout, fields, where)
    if isinstance(layout, Extended):
        known = _paths(layout)
        _check_keys(fields, known, where)
        last = max((g for g, grp in enumerate(layout.groups) for p in grp.fields
                    if fields.get(p) is not None), default=0)
        parts = []
        for g in range(last + 1):
            parts.append(_fixed_bits(layout.groups[g], fields, where))
            if layout.fx[g]:
                parts.append(Bits.from_bools([g < last]))
        return Bits.from_joined(parts)
    if isinstance(layout, Repetitive):
        reps = _repetitions(fields)
        if layout.rep_bytes:
            if len(reps) >= 1 << (8 * layout.rep_bytes):
                raise ValueError(f"{where}: {len(reps)} repetitions do not fit the count")
            parts = [pack(f"u{8 * layout.rep_bytes}", len(reps))]
            parts += [_one_repetition(layout.inner, r, where) for r in reps]
            return Bits.from_joined(parts)
        if not reps:
            raise ValueError(f"{where}: an FX-repetitive item needs at least one repetition")
        parts = []
        for i, r in enumerate(reps):
            parts += [_one_repetition(layout.inner, r, where), Bits.from_bools([i < len(reps) - 1])]
        return Bits.from_joined(parts)
    if isinstance(layout, Compound):
        fields = {layout.aliases.get(k, k): v for k, v in fields.items()}
        present = []
        parts = []
        for sub in layout.subs:
            if sub is None:
                present.append(False)
                continue
            name, sl = sub
            if isinstance(sl, Repetitive):
                here = {k: v for k, v in fields.items() if k == name}
                value: Any = fields.get(name)
            else:
                here = {k: v for k, v in fields.items() if k.split("/")[0] == name and v is not None}
                value = here
            present.append(bool(here))
            if here:
                parts.append(_encode_bits(sl, value, f"{where} {name}"))
        _check_keys(fields, [*_paths(layout), *(s[0] for s in layout.subs if s)], where)
        return Bits.from_joined([_fspec_bits(present), *parts])
    if isinstance(layout, Explicit):
        if isinstance(fields, Mapping):
            _check_keys(fields, ("", "raw"), where)
            if "raw" in fields:
                whole = bytes(fields["raw"])
                if not whole or whole[0] != len(whole):
                    raise ValueError(f"{where}: length byte {whole[:1].hex()} != {len(whole)} bytes given")
                return Bits.from_bytes(whole)
            fields = fields.get("", b"")
        content = bytes(fields)
        if len(content) + 1 > 255:
            raise ValueError(f"{where}: {len(content)} content bytes do not fit a one-byte length")
        return Bits.from_bytes(bytes([len(content) + 1]) + content)
    raise TypeError(layout)


def encode_item(category: int, edition: str | None, item_id: str, fields: Any) -> bytes:
    """One item's bytes from field values keyed by path ("RHO", "SRL/SRL", "" for a bare element).

    Repetitive items take a list (dicts or raw bytes per repetition); explicit items (RE, SP) take the content
    bytes (the length byte is prepended) or {"raw": bytes including the length byte}.
    """
    item = _item(category, edition, item_id)
    where = f"I{category:03d}/{item.id}"
    if not isinstance(fields, Mapping | bytes | bytearray | list | tuple):
        fields = {"": fields}
    return _encode_bits(item.layout, fields, where).tobytes()


# ---------------------------------------------------------------------------------------------------------
# Column plans: which (item, field) each column of an edition writes.


@dataclass(frozen=True)
class _Target:
    item: str
    path: str
    node: Field | Repetitive


@cache
def _targets(category: int, edition: str) -> dict[str, tuple[_Target, ...]]:
    """For each column of the edition, its sources that exist in that edition, in column order."""
    items = _items(category, edition)
    out: dict[str, tuple[_Target, ...]] = {}
    for col in columns_for(category, edition):
        found = []
        for item_id, path in col.sources:
            if item_id not in items:
                continue
            layout = items[item_id].layout
            key = "/".join(path)
            if isinstance(layout, Compound):
                key = layout.aliases.get(key, key)
            node = _paths(layout).get(key)
            if node is not None:
                found.append(_Target(item_id, key, node))
        out[col.name] = tuple(found)
    return out


def _columns(category: int, edition: str) -> dict[str, Column]:
    return {c.name: c for c in columns_for(category, edition)}


# ---------------------------------------------------------------------------------------------------------
# Vectorised record assembly: each part is (present[n], length[n], bytes[n, width]) with rows padded.

_Part = tuple[np.ndarray, np.ndarray, np.ndarray]
_Assigned = dict[str, tuple[np.ndarray, np.ndarray]]  # field path -> (present, raw)


def _column_values(col: Column, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Presence mask and values (object or float array, scale undone) of one column."""
    present = ~pd.isna(values)
    if col.kind in ("float", "int", "flag", "count"):
        out = np.full(len(values), np.nan)
        try:
            out[present] = np.asarray(values[present], dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"column {col.name!r}: non-numeric values") from None
        if col.scale != 1.0:
            out = out / col.scale
        return present, out
    return present, values


def _raw_array(col: Column, target: _Target, present: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Raw field bits (int64, two's complement masked) of one column's present rows, 0 elsewhere."""
    f = target.node
    assert isinstance(f, Field)
    where = f"column {col.name!r} -> I{target.item}"
    raw = np.zeros(len(values), dtype=np.int64)
    idx = np.flatnonzero(present)
    if not len(idx):
        return raw
    if values.dtype == object:
        cache_: dict[Any, int] = {}
        out = np.empty(len(idx), dtype=np.int64)
        for j, i in enumerate(idx):
            v = values[i]
            try:
                out[j] = cache_[v]
            except KeyError:
                out[j] = cache_[v] = _raw(f, v, where)
            except TypeError:  # unhashable
                out[j] = _raw(f, v, where)
        raw[idx] = out
        return raw
    x = values[idx]
    if f.type == "quantity" and col.kind == "float":
        r = np.floor(x / f.lsb + 0.5)
        lo, hi = f.lo, f.hi
    else:
        r = np.round(x)
        bad = np.flatnonzero(r != x)
        if len(bad):
            raise ValueError(f"{_at(f, where)}: row {idx[bad[0]]} value {x[bad[0]]!r} is not an integer")
        # int and flag columns are the field's raw bits, unsigned, as the decoder reads them (fom_pa is 0-15
        # though the 0.2x table prints I021/090 PA as a signed quantity)
        lo, hi = (f.lo, f.hi) if f.type == "integer" and col.kind == "float" else (0, (1 << f.bits) - 1)
    bad = np.flatnonzero((r < lo) | (r > hi))
    if len(bad):
        raise ValueError(f"row {idx[bad[0]]}: " + str(_range_error(f, x[bad[0]], int(r[bad[0]]), where)))
    raw[idx] = r.astype(np.int64) & ((1 << f.bits) - 1 if f.bits < 64 else -1)
    return raw


def _fixed_part(fx: Fixed, assigned: _Assigned, n: int,
                extra_bit: np.ndarray | None = None) -> _Part:
    """A fixed part (optionally followed by an FX bit) as a byte matrix; present if any field is assigned."""
    present = np.zeros(n, dtype=bool)
    total = fx.bits + (extra_bit is not None)
    nbytes = total // 8
    if total <= 64:
        acc = np.zeros(n, dtype=np.uint64)
        for path, f in fx.fields.items():
            if path in assigned:
                mask, raw = assigned[path]
                present |= mask
                acc |= raw.astype(np.uint64) << np.uint64(total - f.offset - f.bits)
        if extra_bit is not None:
            acc |= extra_bit.astype(np.uint64)
        mat = acc.astype(">u8").view(np.uint8).reshape(n, 8)[:, 8 - nbytes:]
    else:  # wider than a machine word: python integers
        ints = [0] * n
        for path, f in fx.fields.items():
            if path in assigned:
                mask, raw = assigned[path]
                present |= mask
                shift = total - f.offset - f.bits
                ints = [a | (int(r) << shift) for a, r in zip(ints, raw, strict=True)]
        if extra_bit is not None:
            ints = [a | int(b) for a, b in zip(ints, extra_bit, strict=True)]
        mat = np.frombuffer(b"".join(a.to_bytes(nbytes, "big") for a in ints), dtype=np.uint8)
        mat = mat.reshape(n, nbytes)
    return present, np.full(n, nbytes, dtype=np.int64), np.ascontiguousarray(mat)


def _concat(parts: list[_Part], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Row-wise concatenation of the present parts: (length[n], bytes[n, width])."""
    width = sum(p[2].shape[1] for p in parts)
    out = np.zeros((n, width), dtype=np.uint8)
    offset = np.zeros(n, dtype=np.int64)
    for present, length, mat in parts:
        length = np.where(present, length, 0)
        cols = np.arange(mat.shape[1])
        rows, cs = np.nonzero(cols[None, :] < length[:, None])
        out[rows, offset[rows] + cs] = mat[rows, cs]
        offset += length
    return offset, out


def _fspec_part(present: list[np.ndarray], n: int) -> _Part:
    """The FSPEC (record or compound) of each row from the presence masks by FRN."""
    nbits = len(present)
    width = max(1, -(-nbits // 7))
    p = np.zeros((n, width * 7), dtype=bool)
    for i, m in enumerate(present):
        p[:, i] = m
    any_ = p.any(axis=1)
    last = np.where(any_, width * 7 - 1 - np.argmax(p[:, ::-1], axis=1), 0)
    length = last // 7 + 1
    weights = np.array([128, 64, 32, 16, 8, 4, 2], dtype=np.uint8)
    mat = (p.reshape(n, width, 7) * weights).sum(axis=2).astype(np.uint8)
    mat |= (np.arange(width)[None, :] < (length - 1)[:, None]).astype(np.uint8)
    return any_, length, mat


def _node_part(layout: Layout, assigned: _Assigned, n: int, where: str) -> _Part:
    """One item or subitem from the assigned fields (zero-filled where unassigned)."""
    if isinstance(layout, Fixed):
        return _fixed_part(layout, assigned, n)
    if isinstance(layout, Extended):
        # groups up to the last one with an assigned (non-missing) field; FX set on all but the last emitted
        present = np.zeros(n, dtype=bool)
        last = np.zeros(n, dtype=np.int64)
        for g, grp in enumerate(layout.groups):
            for p in grp.fields:
                if p in assigned:
                    present |= assigned[p][0]
                    last[assigned[p][0]] = g
        parts = []
        for g, grp in enumerate(layout.groups):
            fx = (g < last) if layout.fx[g] else None
            _, length, mat = _fixed_part(grp, assigned, n, fx)
            parts.append((present & (g <= last), length, mat))
        length, mat = _concat(parts, n)
        return present, length, mat
    if isinstance(layout, Repetitive):
        if layout.path not in assigned:
            return np.zeros(n, dtype=bool), np.zeros(n, dtype=np.int64), np.zeros((n, 0), dtype=np.uint8)
        present, count = assigned[layout.path]
        size = layout.inner.bits // 8 + (layout.rep_bytes is None)
        limit = (1 << (8 * layout.rep_bytes)) - 1 if layout.rep_bytes else None
        lo = 0 if layout.rep_bytes else 1
        bad = np.flatnonzero(present & ((count < lo) | (count > (limit if limit is not None else count))))
        if len(bad):
            raise ValueError(f"{where}: row {bad[0]} repetition count {count[bad[0]]} is out of range")
        count = np.where(present, count, 0)
        head = layout.rep_bytes or 0
        width = head + size * int(count.max(initial=0))
        mat = np.zeros((n, width), dtype=np.uint8)
        for b in range(head):
            mat[:, b] = (count >> (8 * (head - 1 - b))) & 0xFF
        if layout.rep_bytes is None:  # zero elements, FX set on all but the last
            for k in range(int(count.max(initial=0)) - 1):
                mat[:, size * k + size - 1] = (k < count - 1).astype(np.uint8)
        if layout.path + _CODES in assigned and layout.rep_bytes is None and size == 1:  # one-byte codes
            codes = assigned[layout.path + _CODES][1]
            mat[:, :codes.shape[1]] |= (codes << 1).astype(np.uint8)
        return present, head + size * count, mat
    if isinstance(layout, Compound):
        subs = [_node_part(s[1], assigned, n, f"{where} {s[0]}") if s else None for s in layout.subs]
        zero = np.zeros(n, dtype=bool)
        fspec = _fspec_part([s[0] if s else zero for s in subs], n)
        length, mat = _concat([fspec, *(s for s in subs if s)], n)
        return fspec[0], length, mat
    raise ValueError(f"{where}: explicit items cannot be encoded from columns (pass them in `extra`)")


_CODES = "[codes]"  # suffix of an assigned path that holds a repetitive item's element values


def _code_lists(name: str, node: Any, present: np.ndarray, vals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Repetition counts and code matrix (rows padded with 0) of a "codes" column: text such as '3' or
    '1,3' (or a list of ints), each code fitting the repeated element."""
    if not isinstance(node, Repetitive) or node.rep_bytes is not None or node.inner.bits != 7:
        raise ValueError(f"column {name!r}: its item is not a list of 7-bit codes with FX")
    hi = (1 << node.inner.bits) - 1
    lists: list[list[int]] = []
    for i in np.flatnonzero(present):
        v = vals[i]
        parts = v.split(",") if isinstance(v, str) else list(v) if isinstance(v, list | tuple) else [v]
        try:
            codes = [_one_code(c) for c in parts]
        except (TypeError, ValueError):
            raise ValueError(f"column {name!r} row {i}: {v!r} is not a list of codes such as '3' or "
                             f"'1,3'") from None
        if not codes or any(not 0 <= c <= hi for c in codes):
            raise ValueError(f"column {name!r} row {i}: {v!r}: each code must be 0-{hi}")
        lists.append(codes)
    counts = np.zeros(len(vals), np.int64)
    mat = np.zeros((len(vals), max((len(c) for c in lists), default=0)), np.int64)
    for i, codes in zip(np.flatnonzero(present), lists, strict=True):
        counts[i] = len(codes)
        mat[i, :len(codes)] = codes
    return counts, mat


def _one_code(value: Any) -> int:
    """One code of a code list: '3', 3 or 3.0 (a column read back as numbers); ValueError otherwise."""
    if isinstance(value, str):
        return int(value.strip())
    if isinstance(value, bool) or float(value) != int(value):
        raise ValueError(value)
    return int(value)


def _assign(category: int, edition: str, data: Mapping[str, np.ndarray], n: int,
            prefer: Mapping[str, str] | None) -> dict[str, dict[str, tuple[np.ndarray, np.ndarray]]]:
    """Raw values by item and field path from column arrays (multi-source columns last)."""
    cols = _columns(category, edition)
    targets = _targets(category, edition)
    prefer = dict(prefer or {})
    for name in prefer:
        if name not in cols:
            raise ValueError(f"prefer: unknown column {name!r}")
    assigned: dict[str, dict[str, tuple[np.ndarray, np.ndarray]]] = {}
    converted: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for name, values in data.items():
        present, vals = _column_values(cols[name], values)
        if present.any():
            converted[name] = (present, vals)
    single = [c for c in converted if len(targets[c]) <= 1 and c not in prefer]
    multi = [c for c in converted if c not in single]

    def put(name: str, t: _Target, rows: np.ndarray, raw: np.ndarray) -> None:
        slot = assigned.setdefault(t.item, {})
        if t.path in slot:
            old_mask, old_raw = slot[t.path]
            clash = np.flatnonzero(rows & old_mask & (old_raw != raw))
            if len(clash):
                raise ValueError(f"column {name!r} row {clash[0]} conflicts with another column writing "
                                 f"I{category:03d}/{t.item} {t.path!r}")
            slot[t.path] = (rows | old_mask, np.where(rows, raw, old_raw))
        else:
            slot[t.path] = (rows, np.where(rows, raw, 0))

    def raw_of(name: str, t: _Target, present: np.ndarray, vals: np.ndarray) -> np.ndarray:
        if isinstance(t.node, Repetitive):
            bad = np.flatnonzero(present & (vals != np.round(vals)))
            if len(bad):
                raise ValueError(f"column {name!r} row {bad[0]}: count {vals[bad[0]]!r} is not an integer")
            return np.where(present, vals, 0).astype(np.int64)
        return _raw_array(cols[name], t, present, vals)

    for name in single + multi:
        present, vals = converted[name]
        ts = targets[name]
        if not cols[name].sources:
            raise ValueError(f"column {name!r} of CAT{category:03d} is derived on decoding, not sent: "
                             f"{cols[name].doc}")
        if cols[name].kind in BDS_KINDS:
            raise ValueError(f"column {name!r} is read from a Mode S register in I{category:03d}/250 and is "
                             f"not written from its value: pass the register groups as extra={{'250': "
                             f"encode_item({category}, None, '250', [...])}}")
        if not ts:
            raise ValueError(f"column {name!r} has no item in CAT{category:03d} edition {edition}")
        if cols[name].kind == "codes":  # the repetitions themselves, beside their count
            counts, codes = _code_lists(name, ts[0].node, present, vals)
            put(name, ts[0], present, counts)
            assigned[ts[0].item][ts[0].path + _CODES] = (present, codes)
            continue
        if name in prefer:
            want = prefer[name].rsplit("/", 1)[-1].removeprefix("I")
            chosen = [t for t in ts if t.item == want]
            if not chosen:
                raise ValueError(f"prefer: column {name!r} cannot be written to item {prefer[name]!r} in "
                                 f"edition {edition} (sources: {[t.item for t in ts]})")
            put(name, chosen[0], present, raw_of(name, chosen[0], present, vals))
            continue
        rows = present.copy()
        if len(ts) > 1:  # already carried by a source another column wrote with the same value?
            for t in ts:
                slot = assigned.get(t.item, {})
                if t.path in slot:
                    mask, raw = slot[t.path]
                    both = present & mask
                    try:
                        rows &= ~(both & (raw == raw_of(name, t, both, vals)))
                    except ValueError:  # does not fit that source: not carried there
                        pass
        put(name, ts[0], rows, raw_of(name, ts[0], rows, vals))
    return assigned


def _item_parts(category: int, edition: str, data: Mapping[str, np.ndarray], n: int,
                prefer: Mapping[str, str] | None) -> tuple[dict[str, _Part], dict[str, _Assigned]]:
    """The encoded items of n rows, by item id, and the raw field values they were built from."""
    assigned = _assign(category, edition, data, n, prefer)
    items = _items(category, edition)
    parts = {}
    for item_id, fields in assigned.items():
        parts[item_id] = _node_part(items[item_id].layout, fields, n, f"I{category:03d}/{item_id}")
    return parts, assigned


def _row_uaps(category: int, edition: str, parts: dict[str, _Part], assigned: dict[str, _Assigned],
              n: int) -> np.ndarray:
    """The UAP name of each row (all "" for a category with one UAP): its selector field's value (0 where
    the selector item is written without it: zero-filled on the wire)."""
    sel = _selector(category, edition)
    if sel is None:
        return np.full(n, "", dtype=object)
    has = parts[sel.item][0] if sel.item in parts else np.zeros(n, dtype=bool)
    mask, raw = assigned.get(sel.item, {}).get(sel.path, (np.zeros(n, dtype=bool), np.zeros(n, np.int64)))
    value = np.where(mask, raw, 0)
    frn = _items(category, edition)[sel.item].frn
    later = np.zeros(n, dtype=bool)
    for item_id, part in parts.items():
        if _items(category, edition)[item_id].frn > frn:
            later |= part[0]
    out = np.empty(n, dtype=object)
    for v in np.unique(value[has]):
        out[has & (value == v)] = _uap_of(category, edition, int(v), True, "row")
    missing = np.flatnonzero(~has & later)
    if len(missing):
        _uap_of(category, edition, None, True, f"row {missing[0]}")
    out[~has] = _uap_of(category, edition, None, False, "row")
    return out


def _records(category: int, edition: str, data: Mapping[str, np.ndarray], n: int,
             prefer: Mapping[str, str] | None) -> tuple[np.ndarray, np.ndarray]:
    """All records of n rows: (lengths, flat bytes in row order), each laid out by its UAP."""
    parts, assigned = _item_parts(category, edition, data, n, prefer)
    row_uap = _row_uaps(category, edition, parts, assigned, n)
    zero = np.zeros(n, dtype=bool)
    length = np.zeros(n, dtype=np.int64)
    records: list[tuple[np.ndarray, np.ndarray]] = []
    for name, items in _uap_items(category, edition).items():
        rows = row_uap == name
        if not rows.any():
            continue
        by_frn = {}
        for item_id, (present, size, m) in parts.items():
            if item_id in items:
                by_frn[items[item_id].frn] = (present & rows, size, m)
            elif (present & rows).any():
                row = int(np.flatnonzero(present & rows)[0])
                raise ValueError(f"row {row}: I{category:03d}/{item_id} is not an item of its UAP ({name})")
        nfrn = len(uaps(load_table(category, edition))[name])
        fspec = _fspec_part([by_frn[f][0] if f in by_frn else zero for f in range(1, nfrn + 1)], n)
        empty = np.flatnonzero(rows & ~fspec[0])
        if len(empty):
            raise ValueError(f"row {empty[0]} has no value to encode")
        fspec = (fspec[0] & rows, fspec[1], fspec[2])
        uap_length, mat = _concat([fspec, *(by_frn[f] for f in sorted(by_frn))], n)
        length = np.where(rows, uap_length, length)
        records.append((rows, mat))
    width = int(length.max(initial=0))
    mat = np.zeros((n, width), dtype=np.uint8)
    for rows, m in records:
        w = min(width, m.shape[1])
        mat[rows, :w] = m[rows, :w]
    flat = mat[np.arange(width)[None, :] < length[:, None]]
    return length, flat


# ---------------------------------------------------------------------------------------------------------
# Public record, block and frame encoders.


def encode_record(category: int, values: Mapping[str, Any], edition: str | None = None,
                  extra: Mapping[str, bytes] | None = None, prefer: Mapping[str, str] | None = None) -> bytes:
    """One record (FSPEC + items) from column values; `extra` gives complete raw items by item id.

    None/NaN/NA values are absent. Multi-source columns go to their first source (or `prefer[column]`)
    unless another column already wrote the same value to one of their sources. `extra` replaces an item
    built from the values.
    """
    category = _check_category(category)
    ed = _check_edition(category, edition)
    cols = _columns(category, ed)
    hexes = {k: np.array([values[k]], dtype=object) for k in values
             if k.endswith(HEX) and k.removesuffix(HEX) in _identity_columns(category, ed)}
    unknown = [k for k in values if k not in cols and k not in hexes]
    if unknown:
        raise ValueError(f"unknown column(s) for CAT{category:03d} edition {ed}: {unknown}")
    data = {}
    for k, v in values.items():
        if k in hexes:
            continue
        if v is None or v is pd.NA or (isinstance(v, float) and math.isnan(v)):
            continue
        if cols[k].kind in ("float", "int", "flag", "count"):
            try:
                data[k] = np.array([float(v)])
            except (TypeError, ValueError):
                raise ValueError(f"column {k!r}: {v!r} is not a number") from None
        else:
            data[k] = np.array([v], dtype=object)
    _raw_identities(category, ed, data, hexes)
    data = {k: v for k, v in data.items() if not pd.isna(v[0])}
    parts, _ = _item_parts(category, ed, data, 1, prefer)
    raw_items = {item_id: bytes(mat[0, : length[0]]) for item_id, (present, length, mat) in parts.items()
                 if present[0]}
    for item_id, raw in (extra or {}).items():
        raw_items[_item(category, ed, item_id).id] = bytes(raw)
    if not raw_items:
        raise ValueError("record has no value to encode")
    uap = _record_uap(category, ed, raw_items)
    items = _uap_items(category, ed)[uap]
    by_frn = {}
    for item_id, raw in raw_items.items():
        if item_id not in items:
            raise ValueError(f"I{category:03d}/{item_id} is not an item of the record's UAP ({uap})")
        by_frn[items[item_id].frn] = raw
    nfrn = max(item.frn for item in items.values())
    fspec = _fspec_bits([f in by_frn for f in range(1, nfrn + 1)]).tobytes()
    return fspec + b"".join(by_frn[f] for f in sorted(by_frn))


def _record_uap(category: int, edition: str, raw_items: dict[str, bytes]) -> str:
    """The UAP of one record from its item bytes: the selector field as written (also from ``extra``)."""
    sel = _selector(category, edition)
    if sel is None:
        return ""
    frn = _items(category, edition)[sel.item].frn
    later = any(_items(category, edition)[i].frn > frn for i in raw_items)
    if sel.item not in raw_items:
        return _uap_of(category, edition, None, later, "record")
    f = sel.field
    byte = raw_items[sel.item][f.offset // 8]
    value = (byte >> (8 - f.offset % 8 - f.bits)) & ((1 << f.bits) - 1)
    return _uap_of(category, edition, value, later, "record")


def encode_block(category: int, records: Sequence[bytes]) -> bytes:
    """A data block: CAT, LEN (big-endian, counting the 3 header bytes), records (a sequence of encoded
    records, as encode_record gives them)."""
    if isinstance(category, bool) or not isinstance(category, int | np.integer):
        raise TypeError(f"category {category!r}: a category number (an int), not {type(category).__name__}")
    if not 0 <= category <= 255:
        raise ValueError(f"category {category} does not fit a byte")
    if isinstance(records, bytes | bytearray | memoryview | str) or not isinstance(records, Iterable):
        raise TypeError(f"records {records!r:.40}: a sequence of encoded records (bytes each, as "
                        f"encode_record gives them), not {type(records).__name__}; one record is [record]")
    records = list(records)
    for i, record in enumerate(records):
        if not isinstance(record, bytes | bytearray | memoryview):
            raise TypeError(f"records[{i}] {record!r:.40}: an encoded record (bytes), not "
                            f"{type(record).__name__}")
    body = b"".join(records)
    if len(body) + 3 > MAX_BLOCK:
        raise ValueError(f"data block of {len(body) + 3} bytes exceeds {MAX_BLOCK}")
    return bytes([category]) + (len(body) + 3).to_bytes(2, "big") + body


def _frame_arrays(frame: pd.DataFrame, names: Iterable[str]) -> dict[str, np.ndarray]:
    out = {}
    for name in names:
        s = frame[name]
        if pd.api.types.is_numeric_dtype(s.dtype) and not pd.api.types.is_bool_dtype(s.dtype):
            out[name] = s.to_numpy(dtype=float, na_value=np.nan)
        else:
            out[name] = s.to_numpy(dtype=object)
    return out


HEX = "_hex"  # suffix of the column holding an identification item's raw bits (asterix.frames.icao_columns)


def _identity_columns(category: int, edition: str) -> dict[str, int]:
    """The identification columns (``icao``) an edition writes, with the hex digits of their raw bits."""
    targets = _targets(category, edition)
    return {name: targets[name][0].node.bits // 4 for name, col in _columns(category, edition).items()
            if col.kind == "icao" and targets[name] and isinstance(targets[name][0].node, Field)}


def _raw_identities(category: int, edition: str, data: dict[str, np.ndarray], hexes: Mapping[str, np.ndarray]
                    ) -> None:
    """Each identification column written from its ``NAME_hex`` raw bits where given (the exact bytes: an
    all-zero or all-space identification decodes to no text, and was lost), from its text elsewhere. A
    row giving both must agree (the hex read as text is the text; no text, a hex that reads as none): an
    edited or removed text is not overwritten."""
    for name, digits in _identity_columns(category, edition).items():
        if name + HEX not in hexes:
            continue
        raw = hexes[name + HEX]
        text = np.asarray(data.get(name, np.full(len(raw), None, dtype=object)), dtype=object)
        codes, uniques = pd.factorize(raw)  # each distinct value read once; -1 where not given
        exact = []
        for j, h in enumerate(uniques):
            if not isinstance(h, str) or len(h) != digits or not all(c in string.hexdigits for c in h):
                row = int(np.flatnonzero(codes == j)[0])
                raise ValueError(f"column {name + HEX!r} row {row}: {h!r} is not {digits} hex digits (the "
                                 f"item's {digits * 4} bits)")
            exact.append(bytes.fromhex(h))
        given = codes >= 0
        both = given & ~pd.isna(text)
        pairs = pd.DataFrame({"code": codes[both], "text": text[both]}).drop_duplicates()
        for j, t in pairs.itertuples(index=False):
            if icao_text(int(uniques[j], 16)) != str(t).upper().rstrip():
                row = int(np.flatnonzero(both & (codes == j) & (text == t))[0])
                reads = icao_text(int(uniques[j], 16))
                raise ValueError(f"row {row}: {name} {t!r} and {name + HEX} {uniques[j]!r} (which reads "
                                 f"{reads!r}) disagree: drop {name + HEX} to write the text, or make them "
                                 "agree")
        absent = given & pd.isna(text)  # no text: the hex must read as none (all zero or all spaces)
        for j in np.unique(codes[absent]):
            reads = icao_text(int(uniques[j], 16))
            if reads:
                row = int(np.flatnonzero(absent & (codes == j))[0])
                raise ValueError(f"row {row}: {name} absent and {name + HEX} {uniques[j]!r} (which reads "
                                 f"{reads!r}) disagree: drop {name + HEX} to leave the item out, or make "
                                 "them agree")
        out = text.copy()
        holder = np.empty(len(exact), dtype=object)
        holder[:] = exact
        out[given] = holder[codes[given]]
        data[name] = out


def _source_changes(frame: pd.DataFrame) -> np.ndarray:
    """The rows where the data source (sac, sic) differs from the row before, then the row count."""
    n = len(frame)
    key = np.zeros(n, np.int64)
    for name in ("sac", "sic"):
        if name in frame.columns:
            key = key * 512 + pd.to_numeric(frame[name], errors="coerce").fillna(-1).to_numpy(np.int64)
    return np.append(np.flatnonzero(key[1:] != key[:-1]) + 1, n)


def encode_frame(category: int, frame: pd.DataFrame, edition: str | None = None, records_per_block: int = 20,
                 prefer: Mapping[str, str] | None = None) -> bytes:
    """Data blocks for a frame (one record per row, in order), at most records_per_block records and 65535
    bytes per block, each of one data source (a new block where sac or sic changes, as a recorder's).
    Frame columns that are not in the category's schema, derived on decoding (CAT001 time_of_day: write
    truncated_time_of_day and CAT002 messages) or read from I048/250 Mode S registers (their groups are
    written as zeros, bds_count of them) are ignored."""
    category = _check_category(category)
    if not isinstance(frame, pd.DataFrame):
        raise TypeError(f"frame: a pandas DataFrame (one row per record, columns named as decoding names "
                        f"them), not {type(frame).__name__}; pd.DataFrame(rows) makes one of a list of dicts")
    if isinstance(records_per_block, bool) or not isinstance(records_per_block, int | np.integer):
        raise TypeError(f"records_per_block {records_per_block!r}: a positive integer (an int), not "
                        f"{type(records_per_block).__name__}")
    if records_per_block < 1:
        raise ValueError(f"records_per_block {records_per_block!r}: must be a positive integer (at least 1)")
    records_per_block = int(records_per_block)
    ed = _check_edition(category, edition)
    # derived columns (CAT001 time_of_day, made whole from CAT002 on decoding) have no item to write
    # Mode S register columns (I048/250 contents, kind "bds") are not written: bds_count writes the count
    names = [c for c, col in _columns(category, ed).items()
             if c in frame.columns and col.sources and col.kind not in BDS_KINDS]
    hexed = [c + HEX for c in _identity_columns(category, ed) if c + HEX in frame.columns]
    n = len(frame)
    if n == 0:
        return b""
    lengths, flats = [], []
    for start in range(0, n, _CHUNK):
        chunk = frame.iloc[start:start + _CHUNK]
        try:
            arrays = _frame_arrays(chunk, names)
            _raw_identities(category, ed, arrays, {h: chunk[h].to_numpy(dtype=object) for h in hexed})
            length, flat = _records(category, ed, arrays, len(chunk), prefer)
        except ValueError as exc:
            raise ValueError(f"{exc} (rows counted from {start})" if start else str(exc)) from None
        lengths.append(length)
        flats.append(flat)
    length = np.concatenate(lengths)
    flat = np.concatenate(flats).tobytes()
    if length.max() + 3 > MAX_BLOCK:
        row = int(np.argmax(length))
        raise ValueError(f"row {row}: record of {int(length[row])} bytes cannot fit a data block")
    ends = np.cumsum(length)
    starts = ends - length
    cuts = _source_changes(frame)
    out = []
    i = 0
    head = bytes([category])
    while i < n:
        j = min(i + records_per_block, n, int(cuts[np.searchsorted(cuts, i, side="right")]))
        while ends[j - 1] - starts[i] + 3 > MAX_BLOCK:
            j -= 1
        size = int(ends[j - 1] - starts[i]) + 3
        out.append(head + size.to_bytes(2, "big") + flat[starts[i]:ends[j - 1]])
        i = j
    return b"".join(out)
