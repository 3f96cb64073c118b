"""Frames a long span keeps per window, held in files of a folder instead of memory and read back in the
order they came: over a month of windows the main process then holds one sensor's values of one
requirement at a time, when they are pooled, not every sensor's for the whole span."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pandas as pd


class SpilledFrames:
    """A list of frames that lives in ``folder`` (created when the first frame comes): ``append`` writes
    each as a Parquet file of its own, ``concat`` reads them back as ``pd.concat`` of them would be
    (columns, dtypes and values as written: a categorical stays one, but one without any category, which
    Parquet gives back as text)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self._count = 0
        self.rows = 0  # of every frame written

    def append(self, frame: pd.DataFrame) -> None:
        """Write one frame after the others; an OSError (a full disk) says what the file was for."""
        path = self.folder / f"{self._count:07d}.parquet"
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            frame.to_parquet(path, index=False)
        except OSError as exc:
            raise OSError(exc.errno, f"{exc.strerror or exc} (writing values a long span keeps for its "
                          "pooling: TMPDIR chooses their folder)", str(path)) from None
        self._count += 1
        self.rows += len(frame)

    def __len__(self) -> int:
        return self._count

    def frame(self, k: int) -> pd.DataFrame:
        """The k-th frame written (from 0)."""
        if not 0 <= k < self._count:
            raise IndexError(f"{self.folder}: frame {k} of {self._count}")
        return pd.read_parquet(self.folder / f"{k:07d}.parquet")

    def parts(self) -> Iterator[pd.DataFrame]:
        """The frames written, read one at a time in order (a new pass each call)."""
        return (self.frame(k) for k in range(self._count))

    def concat(self) -> pd.DataFrame:
        """Every frame written, in order, as one frame with a fresh index."""
        if not self._count:
            raise ValueError(f"{self.folder}: no frame was written")
        return pd.concat([self.frame(k) for k in range(self._count)], ignore_index=True)
