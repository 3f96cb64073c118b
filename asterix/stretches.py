"""Stretches of a category's blocks that walk under another edition family than the one decoding them
(recordings of different editions laid end to end), found from which blocks walk under which edition.

A block is evidence for the edition decoding it when it walks under it and not under the other family,
against it when the reverse holds; a block walking under both or neither says nothing. Runs of evidence
shorter than ``min_blocks`` are set aside (a damaged block that walks by chance); a stretch of the other
family runs from its first block against to its last, and over the blocks that say nothing around it, up
to the evidence on either side: a block there that walks under both cannot be told apart, so it is not
decoded either.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Stretch:
    """Consecutive blocks of one category, walking under other editions than the one decoding them."""

    first_offset: int  # the first block's offset in the file
    stop_offset: int  # the end of the last block
    blocks: int
    editions: tuple[str, ...]  # the editions every sampled block of the stretch walks under
    decoding: str  # the edition the rest of the category decodes with
    opens: bool = False  # it starts at the first block of the category in the data decoded (a chunk)...
    closes: bool = False  # ... it ends at the last: a stretch may go on in the chunk before or after

    def joined(self, later: Stretch) -> Stretch | None:
        """This stretch and the next one as one, when they meet across a chunk boundary (this one closes
        its chunk, the later one opens its own, no block decoded between: the caller's to know) and
        share editions; else None."""
        common = tuple(e for e in self.editions if e in later.editions)
        if not (self.closes and later.opens and common and self.decoding == later.decoding):
            return None
        return Stretch(self.first_offset, later.stop_offset, self.blocks + later.blocks, common,
                       self.decoding, self.opens, later.closes)


def _runs(evidence: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """(sign, block indices) of each run of equal nonzero evidence, in order."""
    at = np.flatnonzero(evidence)
    if not len(at):
        return []
    signs = evidence[at]
    cuts = np.flatnonzero(np.diff(signs)) + 1
    return [(int(signs[part[0]]), at[part]) for part in np.split(np.arange(len(at)), cuts)]


def foreign_spans(walks_used: np.ndarray, walks_other: np.ndarray, min_blocks: int
                  ) -> tuple[list[tuple[int, int]], int]:
    """Block index spans [first, stop) of the stretches of the other family (module doc), and how many
    blocks outside them are evidence for the edition used."""
    evidence = walks_used.astype(np.int8) - walks_other.astype(np.int8)
    runs = [(sign, idx) for sign, idx in _runs(evidence) if len(idx) >= min_blocks]
    merged: list[tuple[int, list[np.ndarray]]] = []
    for sign, idx in runs:  # runs set aside leave neighbours of one sign: one run
        if merged and merged[-1][0] == sign:
            merged[-1][1].append(idx)
        else:
            merged.append((sign, [idx]))
    spans, used = [], 0
    for i, (sign, parts) in enumerate(merged):
        if sign > 0:
            used += sum(len(p) for p in parts)
            continue
        lo = int(merged[i - 1][1][-1][-1]) + 1 if i > 0 else 0
        hi = int(merged[i + 1][1][0][0]) if i + 1 < len(merged) else len(evidence)
        spans.append((lo, hi))
    return spans, used


def describe(source: str, category: int, stretches: list[Stretch], pin, raw: bool, shown: int = 3) -> str:
    """What a category's stretches of another edition family are and how to decode each: ``source``
    names the input, ``pin(edition)`` writes a pin as the reader takes it (``--edition 21=2.7``), ``raw``:
    a raw stream, which can be cut at a stretch's offsets into a recording of its own."""
    from .families import edition_families, edition_span

    parts = []
    for st in stretches[:shown]:
        span = edition_span(category, st.editions) or "other editions"
        families = {f for f in edition_families(category) for e in st.editions if e in f}
        how = f"pin {pin(st.editions[-1])}" if len(families) == 1 else f"auto chooses among {span}"
        cut = (f"tail -c +{st.first_offset + 1} {source} | head -c {st.stop_offset - st.first_offset} > "
               f"part.ast; " if raw else "")
        parts.append(f"offsets {st.first_offset}-{st.stop_offset - 1} ({st.blocks} blocks) walk under {span} "
                     f"and not under {st.decoding}: decode them on their own ({cut}{how})")
    more = f"; and {len(stretches) - shown} more" if len(stretches) > shown else ""
    several = len(stretches) > 1
    return (f"{source}: CAT{category:03d} decodes as edition {stretches[0].decoding}, but "
            f"{'stretches' if several else 'a stretch'} of it walk{'' if several else 's'} under another "
            f"edition (recordings of different editions laid end to end?) and {'are' if several else 'is'} "
            "withheld: " + "; ".join(parts) + more)
