"""Decode error reasons and the typed exception raised in strict mode."""

from __future__ import annotations

from . import kernel as k

REASONS = {
    k.E_PAST_END: "an FSPEC or item runs past the end of its data block",
    k.E_UNDEFINED_FRN: "the FSPEC sets an FRN the edition does not define",
    k.E_UNDEFINED_SUB: "a compound item sets a subfield the edition does not define",
    k.E_EXPLICIT_LEN: "an explicit item (RE/SP) has a zero length byte",
    k.E_EMPTY_FSPEC: "a record with an empty FSPEC",
    k.E_BAD_LEN: "data block LEN below 3 or past the end of the data",
    k.E_NO_FRAME: "payload does not frame exactly into ASTERIX data blocks",
    k.E_UNKNOWN_CAT: "unknown category",
    k.E_GARBAGE: "bytes that do not start a plausible ASTERIX data block",
    k.E_EMPTY_BLOCK: "a data block with no record",
    k.E_RFS: "the FSPEC sets the Random Field Sequencing (RFS) FRN, which msdc does not walk",
    k.E_NO_UAP: "a record sets items after the item choosing its UAP (I001/020 for CAT001) without that item",
}


class AsterixError(Exception):
    """Base class of msdc decoding errors."""


class EditionWarning(UserWarning):
    """``read`` found most blocks of a category failing under its edition, every one sampled walking under
    another: a likely wrong edition (said, never switched: nothing on the wire says which edition)."""


class UntimedWarning(UserWarning):
    """``read`` decoded CAT001 records whose truncated time of day no CAT002 message of their radar made
    whole (``Recording.untimed``: offsets and reasons): their time_of_day is NaN, not guessed."""


class ContentWarning(UserWarning):
    """``read`` found an input mostly not ASTERIX (bytes skipped, or framed into blocks unlike a recording's),
    not ASTERIX at all, or a category whose records carry values no real report does (asterix.verdict)."""


class DecodeError(AsterixError):
    """Raised in strict mode for the first bad block: names the file, the offset and the reason."""

    def __init__(self, path: str, offset: int, reason: str, category: int | None = None):
        self.path, self.offset, self.reason, self.category = path, offset, reason, category
        cat = f" CAT{category:03d}" if category is not None and category >= 0 else ""
        super().__init__(f"{path}: offset {offset}{cat}: {reason}")


class UnreadableInput(AsterixError):
    """The input cannot be read at all (missing file, permission, unknown format name)."""
