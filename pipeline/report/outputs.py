"""All-or-nothing output writing: a run that fails while writing leaves no new file behind."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def all_or_nothing(*paths: Path | str | None) -> Iterator[None]:
    """Remove, if the body raises, every file it created in the folders of ``paths`` (outputs and the
    figures written beside them), then re-raise: a failed run writes nothing."""
    folders = {Path(p).resolve().parent for p in paths if p}
    before = {folder: set(folder.iterdir()) for folder in folders if folder.is_dir()}
    try:
        yield
    except BaseException:
        for folder, had in before.items():
            for new in set(folder.iterdir()) - had:
                if new.is_file():
                    new.unlink(missing_ok=True)
        raise
