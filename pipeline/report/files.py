"""Writing one output file: an error names the file (``named``)."""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Iterator

_ERRNO_IN_TEXT = re.compile(r"\[errno (\d+)\]", re.IGNORECASE)  # pyarrow's "Detail: [errno 28] ..."


@contextlib.contextmanager
def named(path: str | os.PathLike[str]) -> Iterator[None]:
    """Writing ``path``: an OSError that names no file (pyarrow's, Pillow's, a zip's on a full disk) is
    raised again naming it, with the system's message for its error number."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None:
            raise
        found = _ERRNO_IN_TEXT.search(str(exc))
        code = exc.errno or (int(found.group(1)) if found else None)
        message = os.strerror(code) if code else (exc.strerror or str(exc))
        raise OSError(code, message, os.fspath(path)) from exc
