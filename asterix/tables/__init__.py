"""Per-edition ASTERIX item tables (JSON data, one file per category edition) and their loader."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

HERE = Path(__file__).parent

# Edition aliases: editions whose UAP and item layouts are those of a table we ship.
# CAT048 1.21-1.26 share the UAP and item layouts of 1.27 (the printed specs start at 1.27).
ALIASES: dict[int, dict[str, str]] = {
    48: {**{f"1.{m}": "1.27" for m in range(21, 27)}, "1.x": "1.32"},
    21: {"2.x": "2.7", "0.x": "0.26"},
}
DEFAULT_EDITION = {48: "1.32", 21: "2.7", 34: "1.29"}


def available() -> dict[int, list[str]]:
    """Editions shipped as tables, by category."""
    out: dict[int, list[str]] = {}
    for p in sorted(HERE.glob("cat*_*.json")):
        cat, ed = p.stem[3:].split("_")
        out.setdefault(int(cat), []).append(ed)
    return out


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
