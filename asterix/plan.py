"""What decoding settles over the whole recording before any record is decoded: how each payload is framed
(the block chain as it is, or careful framing), the edition 'auto' chooses, and the categories whose blocks
are withheld as of a wrong edition. Each is settled by a few passes over the file (framing.survey), in memory
that does not grow with it; ``read`` and ``iter_read`` then decode by the same plan, so what they return does
not depend on the chunk size."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import kernel
from .categories import DECODABLE
from .containers import Segments
from .framing import KEEP_ENTRIES, Framed, Framer, Progress, Replay, segment_modes, survey
from .layout import compile_layout
from .reader import (
    DEFAULT_CATEGORIES,
    WRONG_EDITION_MIN_BLOCKS,
    choose_edition,
    framing_walk,
    tables_for,
    walked_editions,
    walking_editions,
)


@dataclass
class Plan:
    """How a recording is decoded: the framing (modes per segment, the tables it walks with), the editions
    of the decoded categories ('auto' replaced by the choice, left 'auto' when the category has no block),
    how 'auto' chose, and per category whose blocks mostly fail: the editions all sampled walk under
    (``fits``) and whether its blocks are withheld as of a wrong edition."""

    seg: Segments
    modes: np.ndarray
    tables: kernel.Framing
    decoded: list[int]
    editions: dict[int, str | None]
    choice: dict[int, str] = field(default_factory=dict)
    fits: dict[int, tuple[str, ...]] = field(default_factory=dict)
    withheld: set[int] = field(default_factory=set)
    framed: Framed | None = None  # the settled framing itself, when careful and short (framing.KEEP_ENTRIES)

    def framer(self, buf: np.ndarray) -> Framer | Replay:
        """The settled framing, to be read window by window (replayed when kept)."""
        if self.framed is not None:
            return Replay(buf, self.seg, self.framed)
        return Framer(buf, self.seg, self.modes, self.tables)


def plan_recording(buf: np.ndarray, seg: Segments, editions: dict, categories,
                   progress: Progress | None = None) -> Plan:
    """Settle the plan over the whole recording (the rules decode_buffer always followed): framing first
    follows the block chain as it is; if the chain breaks, or a decoded block does not walk (a LEN may be
    damaged), the raw stream is framed again carefully, walking the decoded blocks, and the framing that
    walks more bytes stands (a chain holding from end to end wins a tie: blocks that do not walk are then of
    another edition, not damaged)."""
    editions = dict(editions)
    wanted = set(DEFAULT_CATEGORIES if categories is None else categories)
    decoded = [c for c in DECODABLE if c in wanted]
    auto = [c for c in decoded if editions.get(c) == "auto"]
    walked = framing_walk(buf, seg, editions, categories, progress)
    tables = tables_for(walked)
    modes = segment_modes(buf, seg, tables, progress)
    first = survey(buf, seg, modes, tables, sample=auto, sample_failed=decoded, progress=progress,
                   keep=KEEP_ENTRIES)
    framed = first.framed
    choice: dict[int, str] = {}
    for cat in auto:
        if first.blocks[cat]:
            editions[cat], choice[cat] = choose_edition(buf, *first.samples[cat].arrays(), cat,
                                                       total=int(first.blocks[cat]))
    walked2 = walked_editions(editions, categories)  # the chosen editions walked too
    tables2 = tables_for(walked2)
    checked = first if tables2 is tables else survey(buf, seg, modes, tables, tables2, sample_failed=decoded,
                                                     progress=progress, what="walking the blocks")
    careful = np.full(len(modes), kernel.MODE_CAREFUL, np.int8)
    same = tables2 is tables and (modes == careful).all()  # careful framing again would frame alike
    if not seg.exact and not same and (any(checked.failed[c] for c in decoded) or checked.lone(walked)):
        kept = not first.errors and not checked.lone(walked2) and not checked.failed.any()
        if not kept:
            again = survey(buf, seg, careful, tables2, sample=[c for c in auto if c not in choice],
                           sample_failed=decoded, progress=progress, what="framing carefully",
                           keep=KEEP_ENTRIES)
            if first.errors or again.walking_bytes > checked.walking_bytes:
                modes, tables, checked, framed = careful, tables2, again, again.framed
                late = [c for c in auto if c not in choice and again.blocks[c]]
                for cat in late:  # 'auto' categories whose blocks careful framing alone found
                    editions[cat], choice[cat] = choose_edition(buf, *again.samples[cat].arrays(), cat,
                                                           total=int(again.blocks[cat]))
                if late:  # walked under their editions, once chosen
                    walk = tables_for(walked_editions(editions, categories))
                    checked = survey(buf, seg, modes, tables, walk, sample_failed=decoded, progress=progress,
                                     what="walking the blocks")
    plan = Plan(seg, modes, tables, decoded, editions, choice, framed=framed)
    for cat in decoded:
        n_failed, n_blocks = int(checked.failed[cat]), int(checked.blocks[cat])
        if n_failed and 2 * n_failed >= n_blocks:
            plan.fits[cat] = walking_editions(buf, *checked.failed_samples[cat].arrays(), cat,
                                              besides=compile_layout(cat, editions.get(cat)).edition)
            if plan.fits[cat] and n_failed >= WRONG_EDITION_MIN_BLOCKS:
                plan.withheld.add(cat)  # a wrong edition: blocks walking under it would give wrong values
    return plan
