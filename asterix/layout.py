"""Compile an edition table and its column list into flat arrays for the record-walk kernel.

Parts are the walkable units: every UAP item (index = FRN - 1), then every compound subitem.
Fields say where a column's raw bits lie: in which part, at which bit offset, how wide.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from .bds import COLUMN_KIND, field_of
from .columns import BDS_KINDS, Column, columns_for
from .kernel import ABSENT, COMPOUND, EXPLICIT, EXTENDED, FIXED, REP_COUNT, REP_FX, RFS, UNSELECTED, Parts
from .tables import load_table, resolve_edition, uaps

# Output kinds of a field.
OUT_INT, OUT_FLOAT, OUT_WIDE, OUT_FLAG = 0, 1, 2, 3  # int32, float64, int64 and int8 (flags) matrices
FLAG_BITS = 7  # the widest field a flag column (int8, -1 absent) holds


def fixed_bits(node: dict) -> int | None:
    """Bit size of a fixed-size node, or None when its size depends on the data."""
    kind = node["kind"]
    if kind in ("element", "spare", "group"):
        return node["bits"]
    return None


@dataclass(frozen=True)
class Layout:
    """Kernel arrays for one category edition."""

    category: int
    edition: str
    columns: tuple[Column, ...]
    kind: np.ndarray  # int8 per part: an item kind (kernel.FIXED, ...)
    size: np.ndarray  # int32 per part: bytes (fixed), element bytes (repetitive), first group (extended)
    ext_start: np.ndarray  # int32 per part: index into ext_sizes
    ext_count: np.ndarray  # int32 per part
    ext_sizes: np.ndarray  # int32 octet-group sizes of extended parts
    ext_fx: np.ndarray  # int8 per octet-group: 1 when it ends with an FX bit (I021/271 in 2.1: not the last)
    sub_start: np.ndarray  # int32 per part: index into sub_parts (compound)
    sub_count: np.ndarray  # int32 per part
    sub_parts: np.ndarray  # int32 part index of each compound subitem, -1 for a spare position
    slot: np.ndarray  # int32 per part: where the walker records its offset/length, -1 if unused
    n_frn: int
    n_slots: int
    f_slot: np.ndarray  # int32 per field
    f_bit: np.ndarray  # int32 bit offset in the part
    f_bits: np.ndarray  # int32 width
    f_signed: np.ndarray  # bool
    f_out: np.ndarray  # int32 output row
    f_kind: np.ndarray  # int32 OUT_INT / OUT_FLOAT (LSB-scaled) / OUT_WIDE (raw over 31 bits) / OUT_FLAG
    f_mult: np.ndarray  # float64 LSB * column scale
    out_names_float: tuple[str, ...]
    out_names_int: tuple[str, ...]
    out_names_wide: tuple[str, ...]
    out_names_flag: tuple[str, ...]
    item_frn: dict  # item id -> FRN (1-based; of the first UAP that has it)
    selected: tuple[str, ...] | None = None  # the columns compiled (None: all of the edition's)
    code_slots: tuple[tuple[str, int], ...] = ()  # "codes" columns: (name, slot of their repetitive item)
    # "bds" columns: (name, slot of I048/250, register path), read by asterix/bds.py after the gather
    bds_slots: tuple[tuple[str, int, tuple[str, ...]], ...] = ()
    # per part: the UAP selector (byte of the item, right shift, mask; mask 0 for every other part)
    sel_byte: np.ndarray | None = None
    sel_shift: np.ndarray | None = None
    sel_mask: np.ndarray | None = None

    @property
    def P(self) -> np.ndarray:
        """Packed part table for the kernel: kind, size, ext start/count, sub start/count, slot, and the
        UAP selector's byte, shift and mask."""
        return _packed(self, "parts")

    @property
    def parts(self) -> Parts:
        """The part tables ``kernel.scan`` walks records with."""
        return Parts(self.P, self.ext_sizes, self.ext_fx, self.sub_parts)

    @property
    def F(self) -> np.ndarray:
        """Packed field table for the kernel: slot, bit, bits, signed, out row, out kind, fallback."""
        return _packed(self, "fields")


def column_resolution(category: int, column: str, edition: str | None = None) -> tuple[float, ...]:
    """The steps (LSB times the column's scale, in the column's unit) of a float column's source fields, in
    the order the decoder tries them (e.g. I021/131 then /130); () for a column the edition lacks."""
    lay = compile_layout(category, edition, (column,))
    if column not in lay.out_names_float:
        return ()
    row = lay.out_names_float.index(column)
    fields = (lay.f_out == row) & (lay.f_kind == OUT_FLOAT)
    return tuple(float(m) for m in lay.f_mult[fields])


def _fallback(lay: Layout) -> np.ndarray:
    """1 for a field that feeds a column already fed by an earlier field (first present wins)."""
    seen: set[tuple[bool, int]] = set()
    out = np.zeros(len(lay.f_out), np.int64)
    for i, key in enumerate(zip(lay.f_kind.tolist(), lay.f_out.tolist(), strict=True)):
        out[i] = key in seen
        seen.add(key)
    return out


_PACKED: dict[tuple, np.ndarray] = {}


def _packed(lay: Layout, which: str) -> np.ndarray:
    key = (lay.category, lay.edition, lay.selected, which)
    if key not in _PACKED:
        cols = ((lay.kind, lay.size, lay.ext_start, lay.ext_count, lay.sub_start, lay.sub_count, lay.slot,
                 lay.sel_byte, lay.sel_shift, lay.sel_mask)
                if which == "parts" else
                (lay.f_slot, lay.f_bit, lay.f_bits, lay.f_signed, lay.f_out, lay.f_kind, _fallback(lay)))
        _PACKED[key] = np.ascontiguousarray(np.stack([c.astype(np.int64) for c in cols], axis=1))
    return _PACKED[key]


def _fx_flags(node: dict) -> list[bool]:
    """Which octet-groups of an extended node end with an FX bit (from the table: never assumed)."""
    fx = node.get("fx")
    if fx is None or len(fx) != len(node["groups"]):
        raise ValueError("extended item without per-group FX flags: regenerate the tables")
    return [bool(f) for f in fx]


def _locate(node: dict, path: tuple[str, ...]) -> tuple[int, dict] | None:
    """Bit offset and element node of a named field inside a fixed or extended node."""
    kind = node["kind"]
    if not path:
        return (0, node) if kind == "element" else None
    if kind == "element":
        return None
    if kind == "group":
        children = node["items"]
    elif kind == "extended":
        children = [c for g, fx in zip(node["groups"], _fx_flags(node), strict=True)
                    for c in g + ([{"kind": "fx", "bits": 1}] if fx else [])]
    else:
        return None
    bit = 0
    for child in children:
        if child.get("name") == path[0]:
            inner = _locate(child, path[1:]) if child["kind"] != "element" or len(path) > 1 else (0, child)
            return None if inner is None else (bit + inner[0], inner[1])
        bit += child["bits"]
    return None


# Always decoded, whatever the selection: the identity and time every frame is built on (CAT001's whole
# time of day is made from its truncated one, cat001_time)
REQUIRED_COLUMNS = ("sac", "sic", "time_of_day", "truncated_time_of_day")


@dataclass(frozen=True)
class _Selector:
    """Where the value choosing a record's UAP lies in the selector item, and the UAP of each value."""

    frn: int  # FRN of the selector item (the same in every UAP, as is every FRN before it)
    byte: int  # byte of the item holding the field
    shift: int  # right shift of that byte
    mask: int  # field mask after the shift (the field is one to eight bits inside one byte)
    by_value: tuple[str | None, ...]  # UAP name of each value, None where no UAP is named


def _selector(category: int, edition: str, table: dict, named: dict[str, list]) -> _Selector | None:
    """The UAP selector of a table with several UAPs (None with one); ValueError when it cannot be walked
    as data: its item must stand at the same FRN in every UAP, with the same items before it, and its field
    must lie in the item's first octet-group (always present once the item is)."""
    sel = table.get("selector")
    if sel is None:
        return None
    where = f"CAT{category:03d} {edition} UAP selector I{sel['item']}/{'/'.join(sel['field'])}"
    lists = list(named.values())
    frns = {next((e["frn"] for e in u if e and e["id"] == sel["item"]), None) for u in lists}
    if len(frns) != 1 or None in frns:
        raise ValueError(f"{where}: not at one FRN in every UAP")
    frn = frns.pop()
    if any(u[:frn] != lists[0][:frn] for u in lists):
        raise ValueError(f"{where}: the UAPs differ before it")
    node = lists[0][frn - 1]["node"]
    if node["kind"] not in ("element", "group", "extended"):
        raise ValueError(f"{where}: a {node['kind']} item cannot select")
    found = _locate(node, tuple(sel["field"]))
    if found is None:
        raise ValueError(f"{where}: no such field")
    bit, elem = found
    first_bits = fixed_bits(node) or sum(c["bits"] for c in node["groups"][0])
    width = elem["bits"]
    if bit % 8 + width > 8 or bit + width > first_bits or width > 4:
        raise ValueError(f"{where}: the field must lie in one byte of the first octet-group (1-4 bits)")
    by_value = tuple(sel["values"].get(str(v)) for v in range(1 << width))
    return _Selector(frn, bit // 8, 8 - bit % 8 - width, (1 << width) - 1, by_value)


def _frn_rows(named: dict[str, list], selector: _Selector | None) -> tuple[list, int]:
    """The part rows of the FRNs, in blocks of n_frn rows, and n_frn. One UAP: its FRNs. Several: block 0
    holds the FRNs up to the selector and "unselected" rows after it (where a record without the
    selector stops), then one block per selector value, with its UAP's FRNs after the selector (rows up
    to it are never reached: the walk switches blocks once the selector item is walked)."""
    lists = list(named.values())
    n_frn = max(len(u) for u in lists)
    if selector is None:
        return lists[0] + [None] * (n_frn - len(lists[0])), n_frn
    k = selector.frn
    rows: list = lists[0][:k] + [_UNSELECTED] * (n_frn - k)
    for name in selector.by_value:
        if name is None:
            rows += [None] * k + [_UNSELECTED] * (n_frn - k)
        else:
            uap = named[name]
            rows += [None] * k + uap[k:] + [None] * (n_frn - len(uap))
    return rows, n_frn


_UNSELECTED = {"id": None, "node": {"kind": "unselected"}}  # an FRN row of a record whose UAP is not chosen


@cache
def compile_layout(category: int, edition: str | None = None,
                   selected: tuple[str, ...] | None = None) -> Layout:
    """Build the kernel arrays for a category edition (cached); ``selected`` (sorted column names)
    compiles only those columns and ``REQUIRED_COLUMNS``: the walker then records only their items and
    the gather fills only their rows, so memory follows the columns a job needs.

    A category with several UAPs (CAT001) gets one block of FRN rows per selector value (``_frn_rows``);
    the walker moves to a record's block once it has walked the selector item. Rows of one item in
    several UAPs share their slot (a record walks one of them), so a column needs one field."""
    edition = resolve_edition(category, edition)
    table = load_table(category, edition)
    named = uaps(table)
    selector = _selector(category, edition, table, named)
    columns = tuple(c for c in columns_for(category, edition)
                    if selected is None or c.name in selected or c.name in REQUIRED_COLUMNS)
    rows, n_frn = _frn_rows(named, selector)
    parts: list[dict | None] = [u["node"] if u else None for u in rows]
    keys: list = [u["id"] if u else None for u in rows]  # what a part's slot is shared by
    kind, size, ext_start, ext_count, sub_start, sub_count = ([] for _ in range(6))
    ext_sizes: list[int] = []
    ext_fx: list[int] = []
    sub_parts: list[int] = []
    i = 0
    while i < len(parts):
        node = parts[i]
        k, s, es, ec, ss, sc = ABSENT, 0, 0, 0, 0, 0
        if node is not None:
            nk = node["kind"]
            if (bits := fixed_bits(node)) is not None:
                k, s = FIXED, bits // 8
                if selector is not None and i == selector.frn - 1:
                    # the selector is walked off the fixed fast path (which never checks for one): as an
                    # extended item of one octet-group without FX, the same bytes
                    k, es, ec = EXTENDED, len(ext_sizes), 1
                    ext_sizes.append(s)
                    ext_fx.append(0)
            elif nk == "extended":
                k, es = EXTENDED, len(ext_sizes)
                for g, fx in zip(node["groups"], _fx_flags(node), strict=True):
                    ext_sizes.append((sum(c["bits"] for c in g) + fx) // 8)
                    ext_fx.append(int(fx))
                ec, s = len(node["groups"]), ext_sizes[es]
            elif nk == "repetitive":
                bits = fixed_bits(node["item"])
                if bits is None:
                    raise ValueError(f"CAT{category} {edition}: repetitive of variable items unsupported")
                if node["rep_bytes"] is None:
                    k, s = REP_FX, (bits + 1) // 8
                else:
                    k, s = REP_COUNT, bits // 8
                    if node["rep_bytes"] != 1:
                        raise ValueError("only one-byte repetition counts are supported")
            elif nk == "compound":
                k, ss, sc = COMPOUND, len(sub_parts), len(node["subitems"])
                for sub in node["subitems"]:
                    if sub is None:
                        sub_parts.append(-1)
                    else:
                        if sub["node"]["kind"] == "compound":
                            raise ValueError("nested compound items are unsupported")
                        sub_parts.append(len(parts))
                        parts.append(sub["node"])
                        keys.append((keys[i], sub["name"]))
            elif nk == "explicit":
                k = EXPLICIT
            elif nk == "rfs":
                k = RFS
            elif nk == "unselected":
                k = UNSELECTED
        kind.append(k)
        size.append(s)
        ext_start.append(es)
        ext_count.append(ec)
        sub_start.append(ss)
        sub_count.append(sc)
        i += 1
    sel_byte, sel_shift, sel_mask = (np.zeros(len(parts), np.int32) for _ in range(3))
    if selector is not None:
        at = selector.frn - 1
        sel_byte[at], sel_shift[at], sel_mask[at] = selector.byte, selector.shift, selector.mask

    # item id -> FRN (the first UAP's, where an item is in several) and -> its part in the first block
    # that has it (fields are located there; its rows in the other blocks share its slot)
    item_frn: dict[str, int] = {}
    item_part: dict[str, int] = {}
    for r, u in enumerate(rows):
        if u and u["id"] is not None and u["node"]["kind"] not in ("rfs",):
            item_frn.setdefault(u["id"], u["frn"])
            item_part.setdefault(u["id"], r)
            if parts[item_part[u["id"]]] != u["node"]:
                raise ValueError(f"CAT{category:03d} {edition} I{u['id']}: laid out differently in two UAPs")
    slot = [-1] * len(parts)
    slot_of: dict = {}

    def use(p: int) -> int:
        """The slot of part p, shared by every part of the same key (item, or item and subitem)."""
        key = keys[p]
        if key not in slot_of:
            slot_of[key] = len(slot_of)
        for q, other in enumerate(keys):
            if other == key:
                slot[q] = slot_of[key]
        return slot_of[key]

    fields: list[tuple[int, int, int, bool, int, bool, float]] = []
    names_float: list[str] = []
    names_int: list[str] = []
    names_wide: list[str] = []
    names_flag: list[str] = []
    code_slots: list[tuple[str, int]] = []
    bds_slots: list[tuple[str, int, tuple[str, ...]]] = []
    for col in columns:
        if col.kind in BDS_KINDS:  # a Mode S register field, read from the item's bytes after the gather
            found = _bds_item(category, edition, col, item_part, parts)
            if found is not None:
                bds_slots.append((col.name, use(found[0]), found[1]))
            continue
        if col.kind == "codes":  # read from the item's bytes after the gather (reader), not by a field
            p = _code_item(category, edition, col, item_part, parts)
            if p is not None:
                code_slots.append((col.name, use(p)))
            continue
        is_float = col.kind == "float"
        out_kind = {"float": OUT_FLOAT, "icao": OUT_WIDE, "flag": OUT_FLAG}.get(col.kind, OUT_INT)
        names = {OUT_FLOAT: names_float, OUT_INT: names_int, OUT_WIDE: names_wide,
                 OUT_FLAG: names_flag}[out_kind]
        out = len(names)
        names.append(col.name)
        for item_id, path in col.sources:
            if item_id not in item_part:
                continue
            p = item_part[item_id]
            node = parts[p]
            assert node is not None
            if col.kind == "count":
                loc: tuple[int, dict] | None = (0, {"bits": 8, "signed": False, "lsb": 1.0})
            else:
                if node["kind"] == "compound" and path:
                    subs = node["subitems"]
                    names_sub = [s["name"] if s else None for s in subs]
                    if path[0] not in names_sub:
                        continue
                    p = sub_parts[sub_start[p] + names_sub.index(path[0])]
                    node, path = parts[p], path[1:]
                    if node["kind"] == "element" and len(path) == 1:
                        path = ()
                loc = _locate(node, path)
            if loc is None:
                continue
            bit, elem = loc
            if out_kind == OUT_FLAG and elem["bits"] > FLAG_BITS:
                raise ValueError(f"CAT{category:03d} {edition} {col.name}: a flag column of {elem['bits']} "
                                 f"bits (at most {FLAG_BITS})")
            lsb = elem.get("lsb", 1.0) if is_float else 1.0
            fields.append((use(p), bit, elem["bits"], bool(elem.get("signed", False)), out, out_kind,
                           lsb * col.scale))
    n_slots = len(slot_of)
    f = list(zip(*fields, strict=True)) if fields else [[]] * 7
    i32 = np.int32
    return Layout(
        category=category, edition=edition, columns=columns,
        kind=np.array(kind, np.int8), size=np.array(size, i32), ext_start=np.array(ext_start, i32),
        ext_count=np.array(ext_count, i32), ext_sizes=np.array(ext_sizes or [1], i32),
        ext_fx=np.array(ext_fx or [1], np.int8), sub_start=np.array(sub_start, i32),
        sub_count=np.array(sub_count, i32), sub_parts=np.array(sub_parts or [-1], i32),
        slot=np.array(slot, i32), n_frn=n_frn, n_slots=n_slots,
        f_slot=np.array(f[0], i32), f_bit=np.array(f[1], i32), f_bits=np.array(f[2], i32),
        f_signed=np.array(f[3], np.bool_), f_out=np.array(f[4], i32), f_kind=np.array(f[5], i32),
        f_mult=np.array(f[6], np.float64),
        out_names_float=tuple(names_float), out_names_int=tuple(names_int), out_names_wide=tuple(names_wide),
        out_names_flag=tuple(names_flag),
        item_frn=item_frn, selected=selected, code_slots=tuple(code_slots),
        bds_slots=tuple(bds_slots),
        sel_byte=sel_byte, sel_shift=sel_shift, sel_mask=sel_mask,
    )


def _code_item(category: int, edition: str, col: Column, item_part: dict, parts: list) -> int | None:
    """The part of a "codes" column's item: an FX-repetitive item of one-byte repetitions (7-bit code and
    FX), such as I048/030; None when the edition has no such item."""
    for item_id, _ in col.sources:
        if item_id not in item_part:
            continue
        p = item_part[item_id]
        node = parts[p]
        if node["kind"] != "repetitive" or node["rep_bytes"] is not None or node["item"].get("bits") != 7:
            raise ValueError(f"CAT{category:03d} {edition} I{item_id}: column {col.name!r} needs repeated "
                             f"7-bit codes with FX")
        return p
    return None


def _bds_item(category: int, edition: str, col: Column, item_part: dict, parts: list
              ) -> tuple[int, tuple[str, ...]] | None:
    """The part and register path of a "bds" column: a counted repetitive item of 8-byte groups (MB
    data, BDS1, BDS2), such as I048/250; None when the edition has no such item."""
    for item_id, path in col.sources:
        if item_id not in item_part:
            continue
        p = item_part[item_id]
        node = parts[p]
        if node["kind"] != "repetitive" or node["rep_bytes"] != 1 or fixed_bits(node["item"]) != 64:
            raise ValueError(f"CAT{category:03d} {edition} I{item_id}: column {col.name!r} needs counted "
                             f"8-byte BDS register groups")
        _, field = field_of(path)
        if COLUMN_KIND[field.kind] != col.kind:
            raise ValueError(f"column {col.name!r}: register field {'/'.join(path)} decodes as {field.kind}, "
                             f"so its kind is {COLUMN_KIND[field.kind]!r}, not {col.kind!r}")
        return p, path
    return None
