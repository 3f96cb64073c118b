"""Hand-built container bytes shared by the container and command-line tests: pcapng blocks and a UDP
packet in a little-endian pcap, written from the formats' layouts (independent of msdc's readers)."""

from __future__ import annotations

import struct

PCAP_RECORD = 16  # pcap record header bytes
ETH_IP_UDP = 14 + 20 + 8  # header bytes before a UDP payload in the packets built here


def udp_frame(payload: bytes, port: int = 8600) -> bytes:
    """Ethernet II / IPv4 (20 bytes, DF) / UDP carrying payload."""
    udp = struct.pack(">HHHH", 40000, port, 8 + len(payload), 0) + payload
    ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 7, 0x4000, 64, 17, 0,
                     bytes([192, 168, 1, 10]), bytes([239, 1, 1, 1]))
    return b"\x01\x00\x5e\x01\x01\x01" + b"\x00\x11\x22\x33\x44\x55" + b"\x08\x00" + ip + udp


def pcap_file(packets: list[tuple[int, int, bytes]]) -> tuple[bytes, list[int]]:
    """Little-endian microsecond pcap (link type 1); (file bytes, offset of each packet's UDP payload)."""
    out = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
    payload_at = []
    for ts_s, ts_us, frame in packets:
        payload_at.append(len(out) + PCAP_RECORD + ETH_IP_UDP)
        out += struct.pack("<IIII", ts_s, ts_us, len(frame), len(frame)) + frame
    return out, payload_at


def png_block(order: str, block_type: int, body: bytes) -> bytes:
    body += b"\x00" * (-len(body) % 4)
    block_bytes = 12 + len(body)
    return struct.pack(order + "II", block_type, block_bytes) + body + struct.pack(order + "I", block_bytes)


def png_shb(order: str) -> bytes:
    return png_block(order, 0x0A0D0D0A, struct.pack(order + "IHHq", 0x1A2B3C4D, 1, 0, -1))


def png_idb(order: str, link: int, tsresol: int | None = None) -> bytes:
    options = b""
    if tsresol is not None:
        options = struct.pack(order + "HHB3x", 9, 1, tsresol) + struct.pack(order + "HH", 0, 0)
    return png_block(order, 1, struct.pack(order + "HHI", link, 0, 0) + options)


def png_epb(order: str, interface: int, ts: int, packet: bytes) -> bytes:
    fields = struct.pack(order + "IIIII", interface, ts >> 32, ts & 0xFFFFFFFF, len(packet), len(packet))
    return png_block(order, 6, fields + packet)


def png_spb(order: str, packet: bytes) -> bytes:
    return png_block(order, 3, struct.pack(order + "I", len(packet)) + packet)
