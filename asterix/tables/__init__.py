"""Per-edition ASTERIX item tables (JSON data, one file per category edition) and their loader."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

from ..categories import REGISTRY

HERE = Path(__file__).parent

# Edition aliases (editions whose UAP and item layouts are those of a table we ship) and the default
# editions, from the category registry
ALIASES: dict[int, dict[str, str]] = {c: info.aliases for c, info in REGISTRY.items() if info.aliases}
DEFAULT_EDITION = {c: info.default_edition for c, info in REGISTRY.items()}


def available() -> dict[int, list[str]]:
    """Editions shipped as tables, by category, each category's in version order (1.9 before 1.10)."""
    out: dict[int, list[str]] = {}
    for p in sorted(HERE.glob("cat*_*.json")):
        cat, ed = p.stem[3:].split("_")
        out.setdefault(int(cat), []).append(ed)
    return {cat: sorted(eds, key=version) for cat, eds in out.items()}


def version(edition: str) -> tuple[int, ...]:
    """An edition's number as a tuple of ints, to order by ("1.10" after "1.9")."""
    return tuple(int(part) for part in edition.split("."))


def resolve_edition(category: int, edition: str | None) -> str:
    """The shipped table name for a requested edition (default, alias or exact)."""
    if edition is None:
        return DEFAULT_EDITION[category]
    edition = ALIASES.get(category, {}).get(edition, edition)
    if edition not in available().get(category, []):
        known = ", ".join(available().get(category, [])) or "none"
        raise ValueError(f"CAT{category:03d} edition {edition!r} is not supported (tables: {known})")
    return edition


@cache
def load_table(category: int, edition: str | None = None) -> dict:
    """The parsed edition table: {'category', 'edition', 'uap': [item or None by FRN]}."""
    edition = resolve_edition(category, edition)
    return json.loads((HERE / f"cat{category:03d}_{edition}.json").read_text())


def uaps(table: dict) -> dict[str, list[dict | None]]:
    """A table's UAPs by name: {"": uap} for a category with one UAP, {"plot": ..., "track": ...} for
    one whose records choose theirs by an item's value (``table["selector"]``: item, field, value -> name)."""
    return table["uaps"] if "uaps" in table else {"": table["uap"]}
