"""Convert the printed asterix-specs item layouts into msdc's JSON edition tables.

Run by hand when an edition is added: ``python -m msdc.asterix.tables.build ../shared/specs [21 48 ...]``
(category numbers, optional: build only those).
The JSON files it writes are committed; the decoder never reads the printed specs.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

HERE = Path(__file__).parent

# A spare FRN prints as "(spare FRN, no item)" or, in some printouts (CAT021 2.2, 2.3, 2.5), as a bare
# "UapItem_<n>" placeholder with no layout below it: both are FRNs without an item. One placeholder,
# "UapItem_599", stands where the EUROCONTROL UAPs put RFS (Random Field Sequencing: CAT001 FRN 21,
# CAT002 FRN 14, the only printouts with it): it becomes an "rfs" node, which the walker reports rather
# than walks (an RFS field is a count, then FRN-item pairs in any order).
_FRN = re.compile(r"^FRN (\d+): (?:I(\d{3})/(\w+): (.*)|\(spare FRN, no item\)|UapItem_(\d+))$")
_RFS_PLACEHOLDER = "599"
# Several UAPs (CAT001 plot and track): "UAP chosen by I001/020/TYP: 0 -> plot, 1 -> track", then one
# "## UAP <name>" section per UAP.
_SELECTOR = re.compile(r"^UAP chosen by I(\d{3})/(\w+)/([\w/]+): (.*)$")
_UAP_HEAD = re.compile(r"^## UAP (\w+)$")
_ELEMENT = re.compile(r"^element (\d+) bits: (.*)$")
_GROUP = re.compile(r"^group (\d+) bits$")
_SPARE = re.compile(r"^spare (\d+) bits$")
_REP = re.compile(r"^repetitive \(rep bytes=(\w+)\)$")
_OCTET = re.compile(r"^octet-group (\d+):$")
_SUB = re.compile(r"^\[(\d+)\] (\w+): ?(.*)$")
_NO_SUB = re.compile(r"^\[(\d+)\] \(none\)$")  # a compound position with no subitem (CAT034 I034/050)
_NAMED = re.compile(r"^(\w+): ?(.*)$")
_QTY = re.compile(r"^(signed|unsigned) quantity lsb=([-+0-9.e]+) ?(.*)$")


def _content(text: str) -> dict:
    """Element content: how its raw bits become a value."""
    m = _QTY.match(text)
    if m:
        return {"type": "quantity", "signed": m[1] == "signed", "lsb": float(m[2]), "unit": m[3].strip()}
    if text.startswith("string "):
        return {"type": "string", "string": text.split()[1].removeprefix("String")}
    if text.startswith("table"):
        return {"type": "table"}
    if text.startswith("signed integer"):
        return {"type": "integer", "signed": True}
    if text.startswith("unsigned integer"):
        return {"type": "integer", "signed": False}
    return {"type": "raw"}


class _Lines:
    def __init__(self, lines: list[str]):
        self.items = [(len(s) - len(s.lstrip(" ")), s.strip()) for s in lines if s.strip()]
        self.i = 0

    def peek(self) -> tuple[int, str] | None:
        return self.items[self.i] if self.i < len(self.items) else None

    def next(self) -> tuple[int, str]:
        self.i += 1
        return self.items[self.i - 1]


def _node(ls: _Lines) -> dict:
    """Parse one structural node (element, group, extended, repetitive, compound, explicit)."""
    indent, text = ls.next()
    if m := _ELEMENT.match(text):
        return {"kind": "element", "bits": int(m[1]), **_content(m[2])}
    if m := _SPARE.match(text):
        return {"kind": "spare", "bits": int(m[1])}
    if m := _GROUP.match(text):
        return {"kind": "group", "bits": int(m[1]), "items": _children(ls, indent)}
    if m := _REP.match(text):
        rep = None if m[1] == "None" else int(m[1])
        return {"kind": "repetitive", "rep_bytes": rep, "item": _node(ls)}
    if text == "extended (FX)":
        groups, fx = [], []
        while (p := ls.peek()) and p[0] > indent and _OCTET.match(p[1]):
            gi, _ = ls.next()
            children = _children(ls, gi)
            groups.append([c for c in children if c["kind"] != "fx"])
            fx.append(any(c["kind"] == "fx" for c in children))  # I021/271 in 2.1 ends without FX
        return {"kind": "extended", "groups": groups, "fx": fx}
    if text == "compound":
        subs: list[dict | None] = []
        while (p := ls.peek()) and p[0] > indent and (m := _SUB.match(p[1]) or _NO_SUB.match(p[1])):
            ls.next()
            index = int(m[1])
            while len(subs) < index - 1:
                subs.append(None)
            subs.append({"name": m[2], "title": m[3], "node": _node(ls)} if m.re is _SUB else None)
        return {"kind": "compound", "subitems": subs}
    if text.startswith("explicit"):
        return {"kind": "explicit"}
    if text == "FX":
        return {"kind": "fx"}
    if m := _NAMED.match(text):
        child = _node(ls)
        child["name"] = m[1]
        if m[2]:
            child["title"] = m[2]
        return child
    raise ValueError(f"unparsed spec line: {text!r}")


def _children(ls: _Lines, indent: int) -> list[dict]:
    out = []
    while (p := ls.peek()) and p[0] > indent and not _FRN.match(p[1]):
        out.append(_node(ls))
    return out


def _parse_uap(ls: _Lines) -> list[dict | None]:
    """FRN lines and their layouts up to the next "## UAP" heading or the end: [item or None by FRN]."""
    uap: list[dict | None] = []
    while (p := ls.peek()) and not _UAP_HEAD.match(p[1]):
        _, text_line = ls.next()
        m = _FRN.match(text_line)
        if not m:
            raise ValueError(f"expected FRN line, got {text_line!r}")
        if m[5] == _RFS_PLACEHOLDER:
            uap.append({"frn": int(m[1]), "id": "RFS", "title": "Random Field Sequencing",
                        "node": {"kind": "rfs"}})
            continue
        if m[2] is None:
            uap.append(None)
            continue
        node = _node(ls)
        uap.append({"frn": int(m[1]), "id": m[3], "title": m[4], "node": node})
    return uap


def parse_spec(text: str) -> dict:
    """Parse one printed edition into {'category', 'edition', 'uap': [item or None by FRN]}, or, for a
    category with several UAPs, {'category', 'edition', 'uaps': {name: [...]}, 'selector': {...}}: the
    selector names the item and field whose value picks the UAP (``values``: value -> UAP name)."""
    lines = text.splitlines()
    head = re.match(r"# Cat_(\d+)_(\d+)_(\d+)", lines[0])
    assert head, lines[0]
    out: dict = {"category": int(head[1]), "edition": f"{int(head[2])}.{int(head[3])}"}
    sel = _SELECTOR.match(lines[1].strip()) if len(lines) > 1 else None
    ls = _Lines(lines[2:] if sel else lines[1:])
    if not sel:
        out["uap"] = _parse_uap(ls)
        return out
    if int(sel[1]) != out["category"]:
        raise ValueError(f"UAP selector {lines[1]!r} names another category")
    values = {}
    for pair in sel[4].split(","):
        value, _, name = (x.strip() for x in pair.partition("->"))
        values[str(int(value))] = name
    uaps: dict[str, list] = {}
    while ls.peek():
        _, text_line = ls.next()
        m = _UAP_HEAD.match(text_line)
        if not m:
            raise ValueError(f"expected a '## UAP <name>' heading, got {text_line!r}")
        uaps[m[1]] = _parse_uap(ls)
    if set(values.values()) != set(uaps):
        raise ValueError(f"UAP selector names {sorted(set(values.values()))}, sections are {sorted(uaps)}")
    out["uaps"] = uaps
    out["selector"] = {"item": sel[2], "field": sel[3].split("/"), "values": values}
    return out


def all_items(table: dict) -> list[dict]:
    """Every item entry of a table, of every UAP (an item in several UAPs once per UAP)."""
    uaps = table["uaps"].values() if "uaps" in table else [table["uap"]]
    return [item for uap in uaps for item in uap if item]


# Corrections to the printed layouts, each with its reason. (category, item, field) -> changes.
ERRATA: dict[tuple[int, str, str], dict] = {
    # The CAT048 standard gives I048/090 FL as 14-bit two's complement in every edition (1.21 on);
    # the 1.27 and 1.31 printouts mark it unsigned, which would read FL -1 as FL 4095.75.
    (48, "090", "FL"): {"signed": True},
    # The CAT010 standard (1.1) gives I010/202 Vx and Vy an LSB of 0.25 m/s; the printout's 1/16 m/s reads
    # every velocity 4x too slow, and real recordings agree with 0.25 only (|(Vx, Vy)| matches the same
    # report's I010/200 ground speed then: see ../shared/specs/README.md).
    (10, "202", "VX"): {"lsb": 0.25},
    (10, "202", "VY"): {"lsb": 0.25},
}


def apply_errata(table: dict) -> dict:
    """Patch the parsed table with ERRATA (fields found by name inside their item)."""
    for (cat, item_id, name), patch in ERRATA.items():
        if table["category"] != cat:
            continue
        for item in all_items(table):
            if item["id"] == item_id:
                _patch(item["node"], name, patch)
    return table


def _patch(node: dict, name: str, patch: dict) -> None:
    if node.get("name") == name and node["kind"] == "element":
        node.update(patch)
    for child in node.get("items", []) + [c for g in node.get("groups", []) for c in g]:
        _patch(child, name, patch)


def _layout_only(table: dict) -> dict:
    """A table without its edition name: what walking and decoding depend on."""
    return {k: v for k, v in table.items() if k != "edition"}


def main(argv: list[str]) -> int:
    """Convert every printed spec in a folder, or only those of the categories named: ``... specs 34``.

    An edition the category registry lists as an alias (CAT001 1.2 and 1.3 of 1.4) gets no table of its
    own: its printout must parse to the same layout as the table it names, or the build stops."""
    from ..categories import REGISTRY

    src = Path(argv[1] if len(argv) > 1 else "../shared/specs")
    only = {int(c) for c in argv[2:]}  # optional category numbers: build only those
    tables: dict[tuple[int, str], tuple[Path, dict]] = {}
    for path in sorted(src.glob("Cat_*.txt")):
        if only and int(path.name.split("_")[1]) not in only:
            continue
        table = apply_errata(parse_spec(path.read_text()))
        tables[(table["category"], table["edition"])] = (path, table)
    for (cat, edition), (path, table) in tables.items():
        target = REGISTRY[cat].aliases.get(edition) if cat in REGISTRY else None
        if target is not None:
            if (cat, target) not in tables:
                raise ValueError(f"{path.name}: edition {edition} is an alias of {target}, whose printout "
                                 f"is not in {src}")
            if _layout_only(tables[(cat, target)][1]) != _layout_only(table):
                raise ValueError(f"{path.name}: edition {edition} is registered as an alias of {target}, "
                                 f"but its layout differs: give it a table of its own")
            print(f"{path.name}: same layout as {target} (an alias in the category registry): no table")
            continue
        out = HERE / f"cat{cat:03d}_{edition}.json"
        out.write_text(json.dumps(table, indent=1) + "\n")
        print(f"{path.name} -> {out.name}: {len(all_items(table))} items")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
