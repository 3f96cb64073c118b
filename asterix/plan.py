"""What decoding settles over the whole recording before any record is decoded: the edition 'auto' chooses
(reader.choose_editions: a sample of the whole recording along its block chain), how each payload is framed
(the block chain as it is, or careful framing), stretches of another edition family, and the categories whose
blocks are withheld as of a wrong edition. Framing is settled by a few passes over the file (framing.survey),
in memory that does not grow with it; ``read`` and ``iter_read`` then decode by the same plan, so what they
return does not depend on the chunk size."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import kernel
from .categories import DECODABLE
from .containers import Segments
from .families import AUTO, with_defaults
from .framing import KEEP_ENTRIES, Framed, Framer, Progress, Replay, segment_modes, survey
from .layout import compile_layout
from .reader import (
    DEFAULT_CATEGORIES,
    WRONG_EDITION_MIN_BLOCKS,
    _walk_flags,
    choose_edition,
    choose_editions,
    find_stretches,
    tables_for,
    walked_editions,
    walking_editions,
)
from .stretches import Stretch


@dataclass
class Plan:
    """How a recording is decoded: the framing (modes per segment, the tables it walks with), the editions
    of the decoded categories ('auto' replaced by the choice, left 'auto' when the category has no block),
    how 'auto' chose, per category the stretches of another edition family among its blocks, and per
    category whose blocks mostly fail (no stretch): the editions all sampled walk under (``fits``) and
    whether its blocks are withheld as of a wrong edition."""

    seg: Segments
    modes: np.ndarray
    tables: kernel.Framing
    decoded: list[int]
    editions: dict[int, str | None]
    choice: dict[int, str] = field(default_factory=dict)
    fits: dict[int, tuple[str, ...]] = field(default_factory=dict)
    withheld: set[int] = field(default_factory=set)
    stretches: dict[int, list[Stretch]] = field(default_factory=dict)
    framed: Framed | None = None  # the settled framing itself, when careful and short (framing.KEEP_ENTRIES)
    assumed: bool = False  # settled assuming every decoded block walks (plan_recording's ``assume_walking``)

    def framer(self, buf: np.ndarray) -> Framer | Replay:
        """The settled framing, to be read window by window (replayed when kept)."""
        if self.framed is not None:
            return Replay(buf, self.seg, self.framed)
        return Framer(buf, self.seg, self.modes, self.tables)


def plan_recording(buf: np.ndarray, seg: Segments, editions: dict, categories,
                   progress: Progress | None = None, assume_walking: bool = False) -> Plan:
    """Settle the plan over the whole recording. Each 'auto' edition is chosen first, over the whole
    recording (reader.choose_editions); framing then follows the block chain as it is; if the chain breaks,
    or a decoded block does not walk (a LEN may be damaged), the raw stream is framed again carefully,
    walking the decoded blocks, and careful framing stands unless the chain held from end to end and careful
    framing walks no more bytes of the chain's own categories (blocks that do not walk are then of another
    edition, not damaged; random bytes walk as a short block of another category now and then).

    ``assume_walking``: where every payload is taken as it is (no careful framing), framing found no error
    and no category has a lone block, the blocks are not walked: the plan is the one for a recording whose
    decoded blocks all walk (``Plan.assumed``). A decoder that then meets a block that does not walk must
    settle the plan again without it (``read`` does: a walk per block saved, a quarter of decoding)."""
    wanted = set(DEFAULT_CATEGORIES if categories is None else categories)
    decoded = [c for c in DECODABLE if c in wanted]
    editions, choice = choose_editions(buf, seg, with_defaults(dict(editions), decoded), categories)
    auto = [c for c in decoded if editions.get(c) == AUTO]  # no block in the sample: chosen once framed
    walked = walked_editions(editions, categories)
    tables = tables_for(walked)
    modes = segment_modes(buf, seg, tables, progress)
    assumed = assume_walking and not (modes == kernel.MODE_CAREFUL).any()
    first = survey(buf, seg, modes, tables, sample=auto, sample_failed=decoded, progress=progress,
                   keep=KEEP_ENTRIES, walk_blocks=not assumed)
    if assumed and (first.errors or first.lone(walked)):  # careful framing may be tried: walk after all
        assumed = False
        first = survey(buf, seg, modes, tables, sample=auto, sample_failed=decoded, progress=progress,
                       keep=KEEP_ENTRIES)
    framed = first.framed
    for cat in auto:
        if first.blocks[cat]:
            editions[cat], choice[cat] = choose_edition(buf, *first.samples[cat].arrays(), cat,
                                                       total=int(first.blocks[cat]))
    walked2 = walked_editions(editions, categories)  # the chosen editions walked too
    tables2 = tables_for(walked2)
    checked = first if tables2 is tables or assumed else survey(
        buf, seg, modes, tables, tables2, sample_failed=decoded, progress=progress, what="walking the blocks")
    careful = np.full(len(modes), kernel.MODE_CAREFUL, np.int8)
    same = tables2 is tables and (modes == careful).all()  # careful framing again would frame alike
    if not seg.exact and not same and (any(checked.failed[c] for c in decoded) or checked.lone(walked)):
        kept = not first.errors and not checked.lone(walked2) and not checked.failed.any()
        if not kept:
            again = survey(buf, seg, careful, tables2, sample=[c for c in auto if c not in choice],
                           sample_failed=decoded, progress=progress, what="framing carefully",
                           keep=KEEP_ENTRIES)
            among = np.flatnonzero(checked.blocks).tolist()  # the categories of the chain as it is
            if first.errors or again.walking_among(among) > checked.walking_among(among):
                modes, tables, checked, framed = careful, tables2, again, again.framed
                late = [c for c in auto if c not in choice and again.blocks[c]]
                for cat in late:  # 'auto' categories whose blocks careful framing alone found
                    editions[cat], choice[cat] = choose_edition(buf, *again.samples[cat].arrays(), cat,
                                                               total=int(again.blocks[cat]))
                if late:  # walked under their editions, once chosen
                    walk = tables_for(walked_editions(editions, categories))
                    checked = survey(buf, seg, modes, tables, walk, sample_failed=decoded, progress=progress,
                                     what="walking the blocks")
    plan = Plan(seg, modes, tables, decoded, editions, choice, framed=framed, assumed=assumed)
    for cat in decoded:
        n_failed, n_blocks = int(checked.failed[cat]), int(checked.blocks[cat])
        edition = compile_layout(cat, editions.get(cat)).edition if n_failed else ""
        if n_failed >= WRONG_EDITION_MIN_BLOCKS:
            starts, lens = _category_blocks(buf, plan, cat, progress)
            failed = ~_walk_flags(buf, starts, lens, cat, edition)
            found = find_stretches(buf, starts, lens, failed, cat, edition)
            del starts, lens, failed
            if found:
                plan.stretches[cat] = found
                continue
        if n_failed and 2 * n_failed >= n_blocks:
            plan.fits[cat] = walking_editions(buf, *checked.failed_samples[cat].arrays(), cat,
                                              besides=edition)
            if plan.fits[cat] and n_failed >= WRONG_EDITION_MIN_BLOCKS:
                plan.withheld.add(cat)  # a wrong edition: blocks walking under it would give wrong values
    return plan


def _category_blocks(buf: np.ndarray, plan: Plan, cat: int, progress: Progress | None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Starts and lengths of every block of ``cat`` in the settled framing (a pass over the file), to find
    stretches of another edition family among them: only for a category with failed blocks enough to hold
    one (WRONG_EDITION_MIN_BLOCKS), 16 bytes a block."""
    starts: list[np.ndarray] = []
    lens: list[np.ndarray] = []
    framer = plan.framer(buf)
    windows = ([framer.window()] if isinstance(framer, Replay) else
               framer.windows(progress=progress, what=f"finding CAT{cat:03d}'s editions"))
    for framed in windows:
        sel = framed[2] == cat
        starts.append(framed[0][sel].astype(np.int64))
        lens.append(framed[1][sel].astype(np.int64))
    if not starts:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(starts), np.concatenate(lens)
