"""What the command line needs before any job runs, kept free of heavy imports so ``msdc --help`` is fast:
the container formats and the installed version."""

from __future__ import annotations

FORMATS = ("raw", "pcap", "pcapng", "final", "gps", "oradis")


def software_version() -> str:
    """The installed msdc version, or "unknown" when run from a checkout."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("msdc")
    except PackageNotFoundError:
        return "unknown"
