"""The typed-frame schema: which item field feeds each column, per category family, as data.

Each column lists one or more sources ``(item, field path)``; the first source present in a record
wins (I021/131 before I021/130, for instance). Bit positions, LSBs and signedness come from the
edition table, so one column definition serves every edition in which the field exists; "int" and "flag"
columns are the raw bits, never sign-extended (I021/090 PA, printed signed in 0.2x, reads 0-15).
"""

from __future__ import annotations

from .base import BDS_KINDS, Column
from .cat001 import CAT001
from .cat002 import CAT002
from .cat010 import CAT010
from .cat020 import CAT020
from .cat021 import CAT021_V0, CAT021_V2
from .cat034 import CAT034
from .cat048 import CAT048
from .cat062 import CAT062
from .status import CAT019, CAT023, CAT025, CAT063, CAT065

__all__ = ["BDS_KINDS", "Column", "columns_for", "FAMILIES", "KIND_DTYPES", "markdown_schema",
           "CAT048", "CAT021_V2", "CAT021_V0", "CAT034", "CAT001", "CAT002", "CAT010", "CAT020", "CAT062",
           "CAT019", "CAT023", "CAT025", "CAT063", "CAT065"]


# category -> its column list for an edition; a new category adds its module and one line here
BY_CATEGORY = {
    48: lambda edition: CAT048,
    21: lambda edition: CAT021_V0 if edition.startswith("0.") else CAT021_V2,
    34: lambda edition: CAT034,
    1: lambda edition: CAT001,
    2: lambda edition: CAT002,
    10: lambda edition: CAT010,
    20: lambda edition: CAT020,
    62: lambda edition: CAT062,
    19: lambda edition: CAT019,
    23: lambda edition: CAT023,
    25: lambda edition: CAT025,
    63: lambda edition: CAT063,
    65: lambda edition: CAT065,
}


def columns_for(category: int, edition: str) -> list[Column]:
    """The column list of a category edition."""
    return BY_CATEGORY[category](edition)


FAMILIES = {"CAT048 (all editions)": CAT048, "CAT021 2.x (2.1-2.7)": CAT021_V2,
            "CAT021 0.2x (0.23-0.26)": CAT021_V0, "CAT034 (1.27-1.29)": CAT034,
            "CAT001 (1.2-1.4, plot and track UAPs)": CAT001, "CAT002 (1.0-1.2)": CAT002,
            "CAT010 (1.1)": CAT010, "CAT020 (1.9-1.11)": CAT020,
            "CAT062 (1.16-1.21)": CAT062, "CAT019 (1.3)": CAT019, "CAT023 (1.2, 1.3)": CAT023,
            "CAT025 (1.5)": CAT025, "CAT063 (1.6)": CAT063, "CAT065 (1.5)": CAT065}
KIND_DTYPES = {"float": "float64 (NaN if absent)", "int": "Int32", "flag": "Int8", "count": "Int16",
               "octal": "text (categorical)", "hex": "text (categorical)", "icao": "text (categorical)",
               "codes": "text (categorical)", "bds": "float64 (NaN if absent)", "bdsint": "Int16",
               "bdsflag": "Int8", "bdstext": "text (categorical)"}


def markdown_schema() -> str:
    """The column reference (docs/columns.md), generated from the tables above."""
    lines = ["# Frame columns", "", "Generated from `asterix/columns/` by "
             "`python -c 'from msdc.asterix.columns import markdown_schema; print(markdown_schema())'`.",
             "Every frame also has `day` (int64: days after the recording's first day; in raw streams the "
             "first report's day in file order, -1 for a late report before the file's first midnight), "
             "`timestamp` "
             "(datetime64[ns, UTC], NaT when the date is unknown), `block` (data block index in the file: "
             "blocks of every category counted from 0, whatever the chunk size `iter_read` decodes in) "
             "and `offset` (byte offset of the record in the file).",
             "",
             "Identification text (`icao` columns: `callsign`, CAT025's `service_designator`) holds the "
             "6-bit ICAO characters A-Z, space and 0-9, trailing spaces stripped. All-zero codes (code 0 is "
             "no character) and all spaces are absent (`<NA>`); any other code outside that set shows as "
             "`?`, never as a letter. Beside each, `callsign_hex` or `service_designator_hex` (text, "
             "categorical, not in the tables below) keeps the item's raw 48 bits as 12 upper-case hex digits "
             "whenever the record carries the item; the encoder writes a call sign item from "
             "`callsign_hex` where given (an all-zero or all-space identification comes back, not left "
             "out), from `callsign` elsewhere, and refuses a row whose two disagree.", "",
             "Code lists (`codes` columns: `warning_codes`, I048/030 and I020/030) hold every code of a "
             "repetitive item "
             "in wire order, as decimal numbers joined by `,` (`3`, `1,3`), `<NA>` when the record lacks the "
             "item. A first code and a count would drop the codes after the first; text keeps them all and "
             "filters in one line: `f.warning_codes.str.contains(r\"(?:^|,)3(?:,|$)\", na=False)` selects "
             "the plots carrying code 3 (split plot), `f.warning_codes.str.split(\",\").explode()` gives one "
             "row per code. Its cost is small: a presence check over the records (about 10 ms per million "
             "records), then one reading per distinct item.", "",
             "Mode S register fields (`bds` columns, CAT048: source `I250/BDS50/ROLL` is the ROLL field of "
             "the BDS 5,0 register in I048/250) are read from the register the radar declares by BDS1/BDS2, "
             "with the ICAO Doc 9871 layouts of `asterix/bds.py`. A field whose status bit is 0 is absent "
             "(NaN), never 0; a record carrying one register twice gives its first: see "
             "[Mode S registers](decoding/mode-s-registers.md).", ""]
    for family, cols in FAMILIES.items():
        lines += [f"## {family}", "", "| column | unit | dtype | source | meaning |", "|---|---|---|---|---|"]
        for c in cols:
            src = " else ".join(f"I{item}" + (f"/{'/'.join(path)}" if path else "")
                                for item, path in c.sources) or "derived (see meaning)"
            lines.append(f"| `{c.name}` | {c.unit} | {KIND_DTYPES[c.kind]} | {src} | {c.doc} |")
        lines.append("")
    return "\n".join(lines)
