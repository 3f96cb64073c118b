"""Read several recordings into one frame per category, with their provenance (SHA-256, format)."""

from __future__ import annotations

import datetime as dt
import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

import asterix
from asterix.reader import Recording
from pipeline.progress import Progress


@dataclass
class Loaded:
    """Frames of all inputs by category, the recordings they came from, and what each input was."""

    frames: dict[int, pd.DataFrame]
    recordings: list[Recording]
    inputs: list[dict] = field(default_factory=list)
    date: dt.date | None = None

    @property
    def errors(self) -> pd.DataFrame:
        """Every input's skipped-bytes account, one frame."""
        frames = [r.errors for r in self.recordings if len(r.errors)]
        return pd.concat(frames, ignore_index=True) if frames else self.recordings[0].errors.iloc[:0]

    def drop_frames(self) -> None:
        """Free the decoded frames (each input's and their concatenation) once the measurements are built
        from them; the inputs, errors, editions and date stay."""
        self.frames = {}
        for rec in self.recordings:
            rec.frames = {}

    @property
    def editions(self) -> dict[int, str]:
        out: dict[int, str] = {}
        for r in self.recordings:
            out.update(r.editions)
        return out


def sha256(path: Path, chunk: int = 1 << 20) -> str:
    """Hex SHA-256 of a file, read in chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            h.update(block)
    return h.hexdigest()


def _concat(parts: list[pd.DataFrame]) -> pd.DataFrame:
    """Concatenate frames of one category, keeping text columns categorical with merged labels."""
    if len(parts) == 1:
        return parts[0]
    cats = [c for c in parts[0].columns if isinstance(parts[0][c].dtype, pd.CategoricalDtype)]
    labels = {c: pd.Index(sorted(set().union(*(p[c].cat.categories for p in parts))), dtype=object)
              for c in cats}
    parts = [p.assign(**{c: p[c].cat.set_categories(labels[c]) for c in cats}) for p in parts]
    return pd.concat(parts, ignore_index=True)


def load(paths: list[str | Path], *, editions=None, date=None, format: str | None = None,
         categories=None, columns=None, progress: Progress | None = None) -> Loaded:
    """Decode every input into one frame per category, each row tagged with its file (``columns``: only
    those decoded columns, see asterix.read).

    Records keep their own ``timestamp``; ``Loaded.date`` (the earliest known date) dates the records of
    inputs that have none (pipeline.model.time.absolute_time).
    """
    recs: list[Recording] = []
    inputs: list[dict] = []
    for i, p in enumerate(paths):
        p = Path(p)
        if progress:
            progress.step(f"{p.name} ({i + 1}/{len(paths)})")
        rec = asterix.read(p, editions=editions, date=date, format=format, categories=categories,
                           columns=columns)
        recs.append(rec)
        inputs.append({"path": str(p), "sha256": sha256(p), "bytes": rec.size_bytes, "format": rec.format,
                       "records": {int(c): len(f) for c, f in rec.frames.items()},
                       "skipped_blocks": len(rec.errors), "editions": dict(rec.editions)})
    dates = [r.date for r in recs if r.date is not None]
    first = min(dates) if dates else None
    by_cat: dict[int, list[pd.DataFrame]] = {}
    for p, rec in zip(paths, recs, strict=True):
        for cat, frame in rec.frames.items():
            frame = frame.assign(file=pd.Categorical([Path(p).name] * len(frame)))
            by_cat.setdefault(cat, []).append(frame)
    frames = {cat: _concat(parts) for cat, parts in by_cat.items()}
    return Loaded(frames, recs, inputs, first)
