"""Hand-building helpers for decoder tests: FSPECs and data blocks written from the ASTERIX rules.

Kept deliberately naive (and separate from asterix.encode) so tests do not share code with the
implementation they check.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import msdc.asterix as asterix
from msdc.asterix.containers import read_segments

# ../shared beside the repository root (CI clones the repository next to it); a worktree one level
# deeper (worktrees/<name>) finds it one level up.
_ROOT = Path(__file__).resolve().parents[1]
SHARED = next((d for d in (_ROOT.parent / "shared", _ROOT.parent.parent / "shared") if d.is_dir()),
              _ROOT.parent / "shared")


def fspec(*frns: int) -> bytes:
    """FSPEC with the given FRNs set: 7 presence bits per octet, MSB = lowest FRN, FX = LSB."""
    n_octets = (max(frns) + 6) // 7
    out = bytearray(n_octets)
    for frn in frns:
        octet, bit = divmod(frn - 1, 7)
        out[octet] |= 0x80 >> bit
    for i in range(n_octets - 1):
        out[i] |= 1
    return bytes(out)


def block(cat: int, *records: bytes) -> bytes:
    """A data block: CAT, LEN (big-endian, counting the 3 header bytes), records."""
    body = b"".join(records)
    return bytes([cat]) + (len(body) + 3).to_bytes(2, "big") + body


def decode_bytes(data: bytes, **kw) -> asterix.Recording:
    """Decode in-memory bytes as a raw recording."""
    buf = np.frombuffer(data, np.uint8)
    return asterix.decode_buffer(buf, read_segments(buf, kw.pop("fmt", "raw")), path="<test>", **kw)


def mutate(buf: bytearray, data) -> tuple[int, str]:
    """One random damage drawn by Hypothesis's ``data`` (a bit flipped, the tail cut, 1-8 bytes inserted or
    deleted) applied to ``buf`` in place; the offset where it starts and which damage it was."""
    from hypothesis import strategies as st

    pos = data.draw(st.integers(0, len(buf) - 1))
    action = data.draw(st.sampled_from(["flip", "truncate", "insert", "delete"]))
    if action == "flip":
        buf[pos] ^= 1 << data.draw(st.integers(0, 7))
    elif action == "truncate":
        del buf[pos:]
    elif action == "insert":
        buf[pos:pos] = data.draw(st.binary(min_size=1, max_size=8))
    else:
        del buf[pos:pos + data.draw(st.integers(1, 8))]
    return pos, action
