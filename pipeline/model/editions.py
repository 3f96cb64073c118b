"""A wrong edition, told to the user: the decoder's per-chunk evidence (``Recording.edition_fits``: most
blocks of a category fail and every one sampled walks under another edition) folded per input and
category into one warning with the edition to pin. Nothing on the wire says which edition a stream uses,
so msdc says what walks and does not switch by itself."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from msdc.asterix.reader import Recording


@dataclass
class Failed:
    """One input's blocks of one category that could not be decoded, and the editions they all walk under
    (None when no chunk of the input had most of its blocks fail)."""

    blocks: int
    edition: str | None
    fits: tuple[str, ...] | None = None


def fold(notes: dict[tuple[str, int], Failed], rec: Recording) -> None:
    """Add one decoded recording or chunk to ``notes`` (keyed by path and category)."""
    if not len(rec.errors):
        return
    counts = rec.errors["category"].dropna().astype(int).value_counts()
    for cat, n in counts.items():
        note = notes.setdefault((rec.path, int(cat)), Failed(0, rec.editions.get(int(cat))))
        note.blocks += int(n)
        fits = rec.edition_fits.get(int(cat))
        if fits is not None:
            note.fits = fits if note.fits is None else tuple(e for e in note.fits if e in fits)


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
    """One warning per input and category whose blocks mostly failed under an edition other ones fit."""
    return [f"{Path(path).name}: {note.blocks} CAT{cat:03d} block(s) could not be decoded under edition "
            f"{note.edition}{advice(cat, note.fits)}"
            for (path, cat), note in notes.items() if note.fits]


def fits_of(notes: dict[tuple[str, int], Failed], cat: int) -> tuple[str, ...] | None:
    """The editions every input's failed blocks of ``cat`` walk under (None if no input says)."""
    found = [note.fits for (_, c), note in notes.items() if c == cat and note.fits]
    if not found:
        return None
    return tuple(e for e in found[0] if all(e in f for f in found))
