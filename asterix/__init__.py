"""ASTERIX decoding for msdc: CAT048, CAT021 and CAT034 recordings into typed pandas frames.

``read`` decodes a file (raw data blocks, pcap/pcapng, or the "final", GPS and ORADIS recorder
formats) into a Recording with one DataFrame per category and an account of what was skipped;
``iter_read`` streams it in chunks; ``encode`` builds records and data blocks from column values.
"""

from .errors import AsterixError, DecodeError, EditionWarning, UnreadableInput
from .reader import Recording, decode_buffer, parse_date, read
from .stream import iter_read
from .tables import available as available_editions

__all__ = [
    "AsterixError", "DecodeError", "EditionWarning", "Recording", "UnreadableInput", "available_editions",
    "decode_buffer", "iter_read", "parse_date", "read",
]
