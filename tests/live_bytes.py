"""Hand-built ASTERIX bytes and loopback helpers for the live-feed tests (tests/pipeline/live): records
written from the category specifications, not by msdc.asterix.encode."""

from __future__ import annotations

import socket
import struct

from asterix_bytes import block, fspec


def cat048_record(sac: int, sic: int, tod_s: float, *, mode3a_v: int = 0, modec_v: int = 0,
                  code: int = 0o1234, fl: float = 350.0, rho_nm: float = 50.0,
                  theta_deg: float = 90.0, mode3a_g: int = 0, modec_g: int = 0) -> bytes:
    """A CAT048 record (UAP FRN 1-6): I048/010 SAC/SIC, I048/140 time of day (1/128 s), I048/020 (TYP 2,
    no extension), I048/040 rho (1/256 NM) and theta (360/2^16 deg), I048/070 Mode 3/A (V bit 16, G bit
    15, code in 12 bits), I048/090 flight level (V bit 16, G bit 15, 1/4 FL in 14 bits)."""
    tod = round(tod_s * 128)
    return (fspec(1, 2, 3, 4, 5, 6) + bytes([sac, sic]) + tod.to_bytes(3, "big") + bytes([0x40])
            + struct.pack(">HH", round(rho_nm * 256), round(theta_deg / 360 * 65536) % 65536)
            + struct.pack(">H", (mode3a_v << 15) | (mode3a_g << 14) | code)
            + struct.pack(">H", (modec_v << 15) | (modec_g << 14) | (round(fl * 4) & 0x3FFF)))


def cat034_north_marker(sac: int, sic: int, tod_s: float) -> bytes:
    """A CAT034 data block of one north marker: I034/010 SAC/SIC (FRN 1), I034/000 message type 1 (FRN 2),
    I034/030 time of day (FRN 3, 1/128 s)."""
    return block(34, fspec(1, 2, 3) + bytes([sac, sic, 1]) + round(tod_s * 128).to_bytes(3, "big"))


def free_port() -> int:
    """A UDP port of 127.0.0.1 nobody listens on now."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def send_all(datagrams: list[bytes], port: int, host: str = "127.0.0.1") -> None:
    """Send each datagram to host:port on loopback (multicast out of 127.0.0.1 with TTL 0)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        if host.startswith("239."):
            s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, socket.inet_aton("127.0.0.1"))
            s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
            s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        for d in datagrams:
            s.sendto(d, (host, port))


def raw_blocks(data: bytes) -> list[bytes]:
    """The data blocks of a raw recording, by their LEN fields."""
    out, pos = [], 0
    while pos < len(data):
        n = int.from_bytes(data[pos + 1:pos + 3], "big")
        out.append(data[pos:pos + n])
        pos += n
    return out
