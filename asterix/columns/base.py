"""The column record and the helpers every category's column list is written with."""

from __future__ import annotations

from dataclasses import dataclass

NM_PER_S_TO_KT = 3600.0


# Mode S register fields read from I048/250 by asterix/bds.py: float, small int, flag, text
BDS_KINDS = ("bds", "bdsint", "bdsflag", "bdstext")


@dataclass(frozen=True)
class Column:
    """One frame column: its name, sources, how raw bits become a value, and its documentation."""

    name: str
    sources: tuple[tuple[str, tuple[str, ...]], ...]
    # float (LSB-scaled) | int | flag | octal | icao | hex | count | codes | Mode S register (BDS_KINDS)
    kind: str = "float"
    scale: float = 1.0  # applied after the LSB, for unit conversion (NM/s -> kt)
    unit: str = ""
    doc: str = ""


def _c(name: str, item: str, path: str, kind: str = "float", unit: str = "", doc: str = "",
       scale: float = 1.0, also: tuple[tuple[str, str], ...] = ()) -> Column:
    sources = ((item, tuple(path.split("/")) if path else ()),) + tuple(
        (i, tuple(p.split("/")) if p else ()) for i, p in also)
    return Column(name, sources, kind, scale, unit, doc)


def _flags(item: str, names: dict[str, str], doc: str) -> list[Column]:
    return [_c(col, item, field, "flag", doc=f"{doc} {field}") for col, field in names.items()]


_COMMON_ID = [
    _c("sac", "010", "SAC", "int", doc="System Area Code"),
    _c("sic", "010", "SIC", "int", doc="System Identification Code"),
]
