"""What an input turned out to be: the share of its bytes that decoded, what was skipped where, and whether
its records are plausible; said as warnings, and as 'not ASTERIX' for a file none of which is.

Bytes count as undecoded when they were skipped (not ASTERIX, damaged) or lie in oversized blocks of
categories msdc does not decode (what text and random bytes frame into); blocks withheld or skipped as
another edition's are ASTERIX and do not count, nor does damaged container structure (a packet of a link
type msdc does not read: its own error says so), but for a format forced on a file that detection reads as
another (a raw stream read as pcap: its damage is the file not being one). Blocks of other categories that
could be a recording's count as ASTERIX: msdc cannot check them.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .plausible import Implausible

MOSTLY_UNDECODED = 0.5  # of the payload bytes: most of the input is not ASTERIX (a warning; decode fails)
NOT_ASTERIX = 0.9  # of the payload bytes: the input is not ASTERIX at all
IMPLAUSIBLE_SHARE = 0.1  # of a category's records: its records are not what they are read as
SHOWN = 5  # offsets given in a warning
SNIFF_BYTES = 1 << 20  # bytes of each of the three windows sniff decodes
BOUNDS_WORDS = "a position off the Earth or a time of day outside 0-24 h"
DOUBTED = "bytes that are not what they are read as (not ASTERIX, damage, or another edition)"
ODD_SOURCE_WORDS = ("name another data source (SAC/SIC) than most records of their data block, or none, "
                    "which no real recording's block does")


@dataclass
class Tally:
    """One input's account, summed over its chunks (``add`` each decoded Recording)."""

    path: str
    format: str = ""
    size: int = 0
    container: int = 0
    decoded: int = 0
    skipped: int = 0  # bytes skipped that are not another edition's blocks
    oversized: int = 0
    skipped_at: list[int] = field(default_factory=list)  # the first skipped runs' offsets
    skipped_runs: int = 0
    records: dict[int, int] = field(default_factory=dict)
    implausible: dict[int, Implausible] = field(default_factory=dict)
    odd_sources: dict[int, Implausible] = field(default_factory=dict)  # plausible.odd_sources, per category
    damaged: int = 0  # bytes of damaged container structure (counted in ``container`` too)
    damage: list[str] = field(default_factory=list)  # its first distinct reasons
    # the format detection gives a file read under another (forced) one: its damage counts as undecoded
    misread: str = ""

    def add(self, rec) -> None:
        """Fold one decoded Recording (or chunk) of the input in."""
        self.format, self.size = rec.format, rec.size_bytes
        self.container += rec.container_bytes
        self.decoded += rec.decoded_bytes
        self.oversized += rec.oversized_bytes
        errors = rec.errors
        if len(errors):
            # container damage (a packet msdc cannot read) is no evidence either way: set aside with the
            # container bytes, as are blocks of another edition (ASTERIX, said by edition warnings)
            reasons = errors["reason"].astype(str)
            boxed = reasons.str.startswith("container:").to_numpy()
            damaged = int(errors["length"].to_numpy()[boxed].sum())
            self.container += damaged
            self.damaged += damaged
            for why in reasons[boxed].str.removeprefix("container: "):
                if why not in self.damage and len(self.damage) < SHOWN:
                    self.damage.append(why)
            other = {c for c, fits in rec.edition_fits.items() if fits} | set(rec.edition_stretches)
            cats = errors["category"].astype("float64").to_numpy()
            mine = ~np.isin(cats, list(other)) & ~boxed
            self.skipped += int(errors["length"].to_numpy()[mine].sum())
            first = errors["offset"].to_numpy()[mine][:SHOWN].tolist()
            self.skipped_at = sorted(self.skipped_at + first)[:SHOWN]
            self.skipped_runs += int(mine.sum())
        for cat, frame in rec.frames.items():
            self.records[cat] = self.records.get(cat, 0) + len(frame)
        for cat, odd in rec.implausible.items():
            self.implausible[cat] = self.implausible.get(cat, Implausible(0, ())) + odd
        for cat, odd in rec.odd_sources.items():
            self.odd_sources[cat] = self.odd_sources.get(cat, Implausible(0, ())) + odd

    @property
    def _misread_bytes(self) -> int:
        """Damaged container bytes that count as undecoded: those of a misread file (``misread``)."""
        return self.damaged if self.misread else 0

    @property
    def payload(self) -> int:
        """Bytes that are not container structure (a misread file's damage is not structure)."""
        return max(self.size - self.container + self._misread_bytes, 0)

    @property
    def undecoded_share(self) -> float:
        """Share of the payload skipped or in oversized blocks, or damage of a misread file (module doc)."""
        undecoded = self.skipped + self.oversized + self._misread_bytes
        return undecoded / self.payload if self.payload else 0.0

    def not_asterix(self) -> bool:
        """Nothing, or next to nothing, of the input is ASTERIX."""
        return self.payload > 0 and self.undecoded_share >= NOT_ASTERIX

    def warnings(self, head: bytes = b"", *, hint: bool = True, detected: bool = True) -> list[str]:
        """What to tell the user: the input is not ASTERIX (``head``: its first bytes, DETECT_BYTES of them
        to look for a recorder file), most of it is not, or a category's records are implausible; none for
        a sound input. A file read as raw that is a recorder file but for its first frame (``detected``: the
        format was not given) is said to be one instead (``hint``; the jobs' format_hints say it else); a
        format given that detection reads the head otherwise counts the container damage as undecoded."""
        if not detected and head and not self.misread:
            from .containers import detect_format

            found = detect_format(head)
            if self.format and found != self.format:
                return dataclasses.replace(self, misread=found).warnings(head, hint=hint, detected=detected)
        name = Path(self.path).name
        out = []
        recorder = self._recorder(head) if detected and self.undecoded_share >= MOSTLY_UNDECODED else None
        if recorder:
            if hint:
                out.append(recorder_words(self.path, self.skipped_runs, recorder))
        elif self.not_asterix():
            return [not_asterix_text(name, self, head)]
        elif self.undecoded_share >= MOSTLY_UNDECODED:
            out.append(f"{name}: {self.undecoded_share:.0%} of its {self.payload} bytes did not decode "
                       f"({self._where()}): most of it is not ASTERIX{self._detected_words()}")
        return out + self._odd_records(name, many=True)

    def notes(self) -> list[str]:
        """Records no real report would be, too few to doubt the input (under IMPLAUSIBLE_SHARE of their
        category's): said, not failing a decode; their values are kept as the bytes say."""
        return self._odd_records(Path(self.path).name, many=False)

    def _odd_records(self, name: str, *, many: bool) -> list[str]:
        """Per category, its implausible records and those naming another data source than their block:
        those at least IMPLAUSIBLE_SHARE of the category's (``many``) or those under it."""
        out = []
        for cat in sorted(set(self.implausible) | set(self.odd_sources)):
            n = self.records.get(cat, 0)
            for odd, what in ((self.implausible.get(cat), f"hold {BOUNDS_WORDS}, which no real report does"),
                              (self.odd_sources.get(cat), ODD_SOURCE_WORDS)):
                if not n or odd is None or not odd.records or (odd.records >= IMPLAUSIBLE_SHARE * n) != many:
                    continue
                more = ", ..." if odd.records > len(odd.offsets) else ""
                said = (f"{name}: {odd.records} of its {n} CAT{cat:03d} records"
                        f"{f' ({odd.records / n:.0%})' if many else ''} {what} (offsets "
                        f"{', '.join(str(o) for o in odd.offsets)}{more}): ")
                out.append(said + (DOUBTED if many else "likely damaged; kept as the bytes say"))
        return out

    def _recorder(self, head: bytes) -> str | None:
        """The recorder format a raw-read input is but for its first frame (containers.recorder_hint)."""
        from .containers import recorder_hint

        return recorder_hint(head) if self.format == "raw" and head else None

    def failed(self) -> bool:
        """Whether ``warnings`` has something to say (decode then fails unless told otherwise)."""
        return bool(self.warnings())

    def _where(self) -> str:
        """Where the undecoded bytes are."""
        parts = []
        if self.skipped:
            at = ", ".join(str(o) for o in self.skipped_at)
            more = ", ..." if self.skipped_runs > len(self.skipped_at) else ""
            runs = f"{self.skipped_runs} run{'s' if self.skipped_runs > 1 else ''}"
            plural = "s" if self.skipped_runs > 1 else ""
            parts.append(f"{self.skipped} bytes skipped in {runs}, at offset{plural} {at}{more}")
        if self.oversized:
            parts.append(f"{self.oversized} bytes in blocks over 8 KB of categories not decoded, "
                         "unlike a recording's")
        if self._misread_bytes:
            parts.append(f"{self.damaged} bytes that do not read as {self.format}: {'; '.join(self.damage)}")
        return "; ".join(parts)

    def _detected_words(self) -> str:
        """What detection would read a misread file as (a damaged recording of the format told may be
        no longer recognised: which is wrong, the format or the file, is the user's to judge)."""
        if not self.misread:
            return ""
        return f"; read as {self.format} as told (detection would read it as {self.misread})"


def recorder_words(path, skipped_blocks: int, fmt: str) -> str:
    """A file read as raw that reads as a recorder file past its first frame: the --format to give."""
    return (f"{path}: read as a raw ASTERIX stream ({skipped_blocks} block(s) skipped), but past its first "
            f"frame it reads as a {fmt} recording (its first frame damaged?): if it is one, give "
            f"--format {fmt}")


COMPRESSED = (  # (magic bytes, what, the command that decompresses it)
    (b"\x1f\x8b", "gzip", "gunzip"),
    (b"BZh", "bzip2", "bunzip2"),
    (b"\xfd7zXZ\x00", "xz", "unxz"),
    (b"\x28\xb5\x2f\xfd", "zstd", "unzstd"),
    (b"PK\x03\x04", "zip", "unzip"),
)


def compressed(head: bytes) -> str | None:
    """'gzip-compressed: decompress it first (gunzip)' (or bzip2, xz, zstd, zip) for a head that starts
    with that compressor's magic bytes, else None. msdc reads no compressed file."""
    for magic, what, tool in COMPRESSED:
        if head.startswith(magic):
            return f"{what}-compressed: decompress it first ({tool})"
    return None


def not_asterix_text(name: str, tally: Tally, head: bytes, sampled: int = 0) -> str:
    """'NAME is not ASTERIX', what reading it found and what its first bytes are; ``sampled``: the bytes
    read when the account is of windows of a larger file (sniff)."""
    share = f"{math.floor(100 * tally.undecoded_share)}%"  # 100% only when no byte decodes
    of = (f"of {sampled} bytes read at its start, middle and end, {share}" if sampled else
          f"{share} of its {tally.payload} bytes")
    said = (f"read as {tally.format or 'raw'}, {of} frame into no data block that decodes "
            f"({tally._where()}); {head_words(head)}{tally._detected_words()}")
    packed = compressed(head)
    if packed:
        return f"{name} is not ASTERIX but {packed} ({said})"
    return f"{name} is not ASTERIX: {said}"


def head_words(head: bytes) -> str:
    """What the first bytes of a file are: hex, as text when they are, and the block header they make."""
    if not head:
        return "it is empty"
    words = f"it starts with bytes {head[:8].hex(' ')}"
    text = head[:256].decode("utf-8", "ignore")
    if text and sum(c.isprintable() or c in "\t\n\r" for c in text) >= 0.9 * len(text):
        words += f" ({text[:24]!r}...: text)"
    if len(head) >= 3 and head[0] == 0:
        words += ", which cannot start a data block (ASTERIX has no category 0)"
    elif len(head) >= 3:
        words += (f", which as a data block header would be category {head[0]} with LEN "
                  f"{int.from_bytes(head[1:3], 'big')}")
    return words


def sniff(path, format: str | None = None, window: int = SNIFF_BYTES) -> str | None:
    """'NAME is not ASTERIX: ...' for a file read as a raw stream (``format`` None or 'raw') of which
    neither the head, the middle nor the tail (``window`` bytes each, decoded on their own; the head up to
    the end of its block chain's last whole block in it) is ASTERIX: said at once, before the whole
    file is decoded. None otherwise, and for a container format."""
    from .containers import DETECT_BYTES, Segments, detect_format, recorder_hint
    from .reader import _mapped, decode_buffer
    from .sampling import chain_end

    with _mapped(path) as buf:
        head = buf[:DETECT_BYTES].tobytes()
        if not len(buf) or (format or detect_format(head)) != "raw" or format is None and recorder_hint(head):
            return None  # a container, or a recorder file whose first frame is damaged (format_hint)
        size = len(buf)
        seen = Tally(str(path))  # every window's account together
        end = 0
        for lo in sorted({0, max(size // 2 - window // 2, 0), max(size - window, 0)}):
            hi = min(lo + window, size)
            if lo < end or hi <= lo:
                continue
            if lo == 0 and hi < size:
                hi = chain_end(buf, 0, hi) or hi  # a head that chains is not cut inside a block
            part = Segments("raw", np.array([lo]), np.array([hi]), np.array([-1]), np.array([np.nan]), False,
                            False, 0, [])
            rec = decode_buffer(buf, part, path=str(path))
            tally = Tally(str(path))
            tally.add(rec)
            tally.size = hi - lo
            if not tally.not_asterix():
                return None
            read_bytes = seen.size + hi - lo
            seen.add(rec)
            seen.size, end = read_bytes, hi
        return not_asterix_text(Path(path).name, seen, bytes(buf[:256]), seen.size if seen.size < size else 0)


def head_of(path, n: int = 1 << 17) -> bytes:
    """The first ``n`` bytes of a file (containers.DETECT_BYTES; b"" when it cannot be read: the decoder
    has said why)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(n)
    except OSError:
        return b""
