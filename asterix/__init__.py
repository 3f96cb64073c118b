"""ASTERIX decoding for msdc: CAT048, CAT021, CAT034, CAT001 and CAT002 recordings into typed pandas frames.

``read`` decodes a file (raw data blocks, pcap/pcapng, or the "final", GPS and ORADIS recorder
formats) into a Recording with one DataFrame per category and an account of what was skipped;
``iter_read`` streams it in chunks; ``encode`` builds records and data blocks from column values.

The names below are loaded on first use (PEP 562), as ``msdc``'s are: importing a light module of the
package (``msdc.asterix.categories``, the category registry the command line reads) imports no numpy.
"""

from __future__ import annotations

import importlib
import importlib.util
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # what the names are, for readers and the API docs; loaded by __getattr__
    from .errors import (
        AsterixError,
        ContentWarning,
        DecodeError,
        EditionWarning,
        UnreadableInput,
        UntimedWarning,
    )
    from .reader import Recording, decode_buffer, parse_date, read
    from .stream import iter_read
    from .tables import available as available_editions

# name -> (module, attribute)
_PUBLIC = {
    "AsterixError": ("errors", "AsterixError"), "DecodeError": ("errors", "DecodeError"),
    "ContentWarning": ("errors", "ContentWarning"),
    "EditionWarning": ("errors", "EditionWarning"), "UnreadableInput": ("errors", "UnreadableInput"),
    "UntimedWarning": ("errors", "UntimedWarning"),
    "Recording": ("reader", "Recording"), "decode_buffer": ("reader", "decode_buffer"),
    "parse_date": ("reader", "parse_date"), "read": ("reader", "read"), "iter_read": ("stream", "iter_read"),
    "available_editions": ("tables", "available"),
}

__all__ = [  # the names of _PUBLIC
    "AsterixError", "ContentWarning", "DecodeError", "EditionWarning", "Recording", "UnreadableInput",
    "available_editions", "decode_buffer", "iter_read", "parse_date", "read", "UntimedWarning",
]


def __getattr__(name: str):
    """A public name, or a submodule (``msdc.asterix.reader``), imported when first used."""
    if name in _PUBLIC:
        module, attribute = _PUBLIC[name]
        value = getattr(importlib.import_module(f"{__name__}.{module}"), attribute)
    elif not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
