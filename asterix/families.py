"""Edition families: a category's editions grouped by how their layouts walk a record.

Two editions are one family when every byte string walks alike under both (the same records, the same
bytes per item): they can only differ in what the bits mean. A category with more than one family is read
with ``editions={cat: "auto"}`` unless pinned: a wrong family turns blocks into errors or into nonsense,
and nothing on the wire says which family a stream uses.
"""

from __future__ import annotations

from functools import cache

from . import kernel as k
from .categories import REGISTRY
from .layout import Layout, compile_layout
from .tables import available

AUTO = "auto"


def _part(lay: Layout, p: int) -> tuple | None:
    """How part ``p`` is walked (None: absent), in a canonical form: an extended item's octet-groups past
    the first one without an FX bit are never read, and trailing copies of its last FX group change
    nothing (the walker repeats the last group); trailing absent compound subitems are refused alike."""
    P = lay.P
    kind = int(P[p, k.K_KIND])
    if kind == k.ABSENT:
        return None
    if kind in (k.FIXED, k.REP_COUNT, k.REP_FX):
        return (kind, int(P[p, k.K_SIZE]))
    if kind == k.EXPLICIT:
        return (kind,)
    if kind == k.EXTENDED:
        s, n = int(P[p, k.K_EXT_START]), int(P[p, k.K_EXT_COUNT])
        groups = [(int(lay.ext_sizes[s + i]), int(lay.ext_fx[s + i])) for i in range(n)]
        ends = [i for i, (_, fx) in enumerate(groups) if not fx]
        if ends:
            groups = groups[:ends[0] + 1]
        else:
            while len(groups) > 1 and groups[-1] == groups[-2]:
                groups.pop()
        return (kind, tuple(groups))
    s, n = int(P[p, k.K_SUB_START]), int(P[p, k.K_SUB_COUNT])
    subs = [_part(lay, int(lay.sub_parts[s + i])) if lay.sub_parts[s + i] >= 0 else None for i in range(n)]
    return (kind, _trimmed(subs))


def _trimmed(items: list) -> tuple:
    """Without trailing Nones (an FRN or subitem past the end is refused as an absent one is)."""
    while items and items[-1] is None:
        items.pop()
    return tuple(items)


def walk_signature(category: int, edition: str) -> tuple:
    """How an edition's UAP walks records, FRN by FRN, in a canonical form: equal for editions under which
    every byte string walks alike (kernel.walks)."""
    lay = compile_layout(category, edition)
    return _trimmed([_part(lay, f) for f in range(lay.n_frn)])


@cache
def edition_families(category: int) -> tuple[tuple[str, ...], ...]:
    """The category's shipped editions grouped into families (editions that walk alike), oldest first."""
    eds = sorted(available().get(category, []), key=lambda e: tuple(int(x) for x in e.split(".")))
    groups: dict[tuple, list[str]] = {}
    for ed in eds:
        groups.setdefault(walk_signature(category, ed), []).append(ed)
    return tuple(tuple(g) for g in groups.values())


def family_of(category: int, edition: str) -> tuple[str, ...]:
    """The family an edition belongs to."""
    return next(f for f in edition_families(category) if edition in f)


def family_name(family: tuple[str, ...]) -> str:
    """'0.23', or '2.2-2.7' for a family of several editions."""
    return family[0] if len(family) == 1 else f"{family[0]}-{family[-1]}"


@cache
def reading_default(category: int) -> str:
    """The edition a category is read with when none is pinned: 'auto' when its editions fall into more
    than one family, else its registry default (one table reads every edition alike)."""
    return AUTO if len(edition_families(category)) > 1 else REGISTRY[category].default_edition


def with_defaults(editions: dict[int, str], categories) -> dict[int, str]:
    """``editions`` with the reading default of each category in ``categories`` that is not pinned."""
    return {**{c: reading_default(c) for c in categories if c not in editions and c in REGISTRY}, **editions}


def edition_span(category: int, editions: tuple[str, ...]) -> str:
    """Editions as a reader says them: '0.23', '2.1-2.7' for a run of consecutive shipped editions, else
    listed ('0.24, 0.26')."""
    order = sorted(available().get(category, []), key=lambda e: tuple(int(x) for x in e.split(".")))
    at = sorted(order.index(e) for e in editions if e in order)
    if len(at) > 1 and at == list(range(at[0], at[-1] + 1)):
        return f"{order[at[0]]}-{order[at[-1]]}"
    return ", ".join(order[i] for i in at)
