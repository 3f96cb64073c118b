"""A part's integrity: its size and CRC-32 as ingest wrote it (recorded in the manifest), checked before a
query reads it. DuckDB does not verify Parquet page checksums: bytes damaged inside a page were read as other
values, silently."""

from __future__ import annotations

import re
import zlib
from dataclasses import dataclass, field
from pathlib import Path

READ_BYTES = 1 << 20  # a part is read this much at a time to checksum it
CHECK_THREADS = 2  # parts checksummed at once (zlib computes without the GIL)
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


def damage(root: Path, part: dict) -> str | None:
    """Why a part the manifest lists is not as ingest wrote it (missing, another size, other bytes,
    unreadable); None when it is, or when the manifest records no checksum for it (a dataset written before
    msdc recorded them: only its presence is checked)."""
    path = root / part["path"]
    try:
        size_bytes = path.stat().st_size
        if "crc32" not in part:
            return None
        if size_bytes != part["size_bytes"]:
            return f"it holds {size_bytes:,} bytes where ingest wrote {part['size_bytes']:,}"
        _, crc = part_checksum(path)
    except FileNotFoundError:
        return "it is missing"
    except OSError as exc:
        return f"it cannot be read ({exc.strerror or exc})"
    if crc != part["crc32"]:
        return (f"its bytes are not those ingest wrote (CRC-32 {crc} where the manifest records "
                f"{part['crc32']})")
    return None


@dataclass
class Checked:
    """The parts checked: those damaged (the manifest's part record, why) and how many carry no checksum."""

    damaged: list[tuple[dict, str]] = field(default_factory=list)
    unverified: int = 0


def check_parts(root: Path, inputs: list[dict], categories: set[int]) -> Checked:
    """Check every part of ``categories`` the manifest's ``inputs`` list (each part record with its input's
    ``file`` label added as ``input``), CHECK_THREADS at a time."""
    from concurrent.futures import ThreadPoolExecutor

    parts = [{**p, "input": rec["file"]} for rec in inputs for p in rec["parts"]
             if int(p["category"]) in categories]
    with ThreadPoolExecutor(CHECK_THREADS, thread_name_prefix="msdc-check") as pool:
        reasons = list(pool.map(lambda p: damage(root, p), parts))
    checked = Checked(unverified=sum("crc32" not in p for p in parts))
    checked.damaged = [(p, why) for p, why in zip(parts, reasons, strict=True) if why is not None]
    return checked


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
