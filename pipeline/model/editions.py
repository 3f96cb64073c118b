"""A wrong edition, told to the user: the decoder's per-chunk evidence folded per input and category into
one warning. ``Recording.edition_fits``: most blocks of a category fail and every one sampled walks under
another edition (the warning gives the edition to pin); ``Recording.edition_stretches``: stretches of the
category walk under another edition family than the rest (recordings of different editions laid end to
end: the warning says where each stretch lies and how to decode it), joined across chunk boundaries.
Nothing on the wire says which edition a stream uses, so msdc says what walks and does not switch by
itself."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from msdc.asterix.reader import Recording
from msdc.asterix.stretches import Stretch, describe


@dataclass
class Failed:
    """One input's blocks of one category that could not be decoded, and the editions they all walk under
    (None when no chunk of the input had most of its blocks fail); the stretches of another edition family
    found in it, and whether any block of the category decoded."""

    blocks: int
    edition: str | None
    fits: tuple[str, ...] | None = None
    stretches: list[Stretch] = field(default_factory=list)
    decoded: bool = False  # some block of the category decoded (in a chunk without fits)
    format: str = ""
    decoded_since: bool = False  # a block decoded after the last stretch (it cannot join the next)


def fold(notes: dict[tuple[str, int], Failed], rec: Recording) -> None:
    """Add one decoded recording or chunk to ``notes`` (keyed by path and category)."""
    counts = dict(rec.errors["category"].dropna().astype(int).value_counts()) if len(rec.errors) else {}
    decoded = {c: n for c, n in rec.decoded_blocks.items() if n}
    for cat in sorted({int(c) for c in counts} | set(rec.edition_stretches) | set(decoded)):
        note = notes.setdefault((rec.path, cat), Failed(0, rec.editions.get(cat), format=rec.format))
        note.blocks += int(counts.get(cat, 0))
        note.decoded = note.decoded or cat in decoded
        fits = rec.edition_fits.get(cat)
        if fits is not None:
            note.fits = fits if note.fits is None else tuple(e for e in note.fits if e in fits)
        pieces = list(rec.edition_stretches.get(cat, []))
        if fits and cat not in decoded:  # the chunk withheld whole: one stretch, to join its neighbours
            errs = rec.errors[rec.errors["category"] == cat]
            first, stop = int(errs["offset"].min()), int((errs["offset"] + errs["length"]).max())
            pieces = [Stretch(first, stop, len(errs), fits, rec.editions.get(cat, ""), True, True)]
        for piece in pieces:
            last = note.stretches[-1] if note.stretches and not note.decoded_since else None
            joined = last.joined(piece) if last is not None else None
            if joined is not None:
                note.stretches[-1] = joined
            else:
                note.stretches.append(piece)
            note.decoded_since = False
        # a block decoded after the last stretch parts it from the next one
        note.decoded_since = (not pieces[-1].closes) if pieces else (note.decoded_since or cat in decoded)


def notes_of(recordings: list[Recording]) -> dict[tuple[str, int], Failed]:
    """``fold`` over every recording."""
    notes: dict[tuple[str, int], Failed] = {}
    for rec in recordings:
        fold(notes, rec)
    return notes


def advice(cat: int, fits: tuple[str, ...] | None) -> str:
    """What to pin, when the failed blocks all walk under other editions ('' when they do not)."""
    if not fits:
        return ""
    if len(fits) == 1:
        return f"; every one sampled decodes under {fits[0]}: pin it with --edition {cat}={fits[0]}"
    return (f"; every one sampled decodes under {', '.join(fits)}: pin the right one or try "
            f"--edition {cat}=auto")


def warnings(notes: dict[tuple[str, int], Failed]) -> list[str]:
    """One warning per input and category whose blocks mostly failed under an edition other ones fit (no
    block of it decoded), or that holds stretches of another edition family beside decoded ones."""
    out = []
    for (path, cat), note in notes.items():
        if note.stretches and note.decoded:
            out.append(describe(Path(path).name, cat, note.stretches, lambda ed, c=cat: f"--edition {c}={ed}",
                                note.format == "raw"))
        elif note.fits:
            out.append(f"{Path(path).name}: {note.blocks} CAT{cat:03d} block(s) could not be decoded under "
                       f"edition {note.edition}{advice(cat, note.fits)}")
    return out


def fits_of(notes: dict[tuple[str, int], Failed], cat: int) -> tuple[str, ...] | None:
    """The editions every input's failed blocks of ``cat`` walk under (None if no input says)."""
    found = [note.fits for (_, c), note in notes.items() if c == cat and note.fits]
    if not found:
        return None
    return tuple(e for e in found[0] if all(e in f for f in found))
