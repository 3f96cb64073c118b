"""A part's integrity: its size and CRC-32 as ingest wrote it (recorded in the manifest), checked before a
query reads it. DuckDB does not verify Parquet page checksums: bytes damaged inside a page were read as other
values, silently."""

from __future__ import annotations

import re
import zlib
from pathlib import Path

READ_BYTES = 1 << 20  # a part is read this much at a time to checksum it
CRC_TEXT = re.compile(r"[0-9a-f]{8}")  # a part's crc32 as the manifest writes it


def part_checksum(path: Path) -> tuple[int, str]:
    """The file's size in bytes and its CRC-32 (8 hex digits, zlib's, over every byte)."""
    crc, size_bytes = 0, 0
    buffer = bytearray(READ_BYTES)
    view = memoryview(buffer)
    with open(path, "rb", buffering=0) as fh:
        while n := fh.readinto(buffer):
            crc = zlib.crc32(view[:n], crc)
            size_bytes += n
    return size_bytes, f"{crc:08x}"


def record_problem(part: dict) -> str | None:
    """What makes a part's recorded size or CRC-32 unreadable (the manifest's check); None when both read, or
    are both absent."""
    if "crc32" not in part and "size_bytes" not in part:
        return None
    if type(part.get("size_bytes")) is not int or part["size_bytes"] < 0:
        return f"size_bytes {part.get('size_bytes')!r} is no count"
    if not isinstance(part.get("crc32"), str) or not CRC_TEXT.fullmatch(part["crc32"]):
        return f"crc32 {part.get('crc32')!r} is no CRC-32 (8 hex digits)"
    return None
