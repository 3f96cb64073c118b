"""What the command line needs before any job runs, kept free of heavy imports so ``msdc --help`` is fast:
the container formats, the installed version, and the choices and ranges the steps share with the options
that take them (pipeline.jobs.options declares those)."""

from __future__ import annotations

FORMATS = ("raw", "pcap", "pcapng", "final", "gps", "oradis")
# replay: the containers it sends, each datagram at its recorded time (raw: block by block; ORADIS has no
# capture times to pace them by)
REPLAYED_FORMATS = ("raw", "pcap", "pcapng", "final", "gps")
# correlate: the sensor pairs correlated per aircraft ("all": radar-adsb and radar-radar)
PAIRS = ("radar-adsb", "radar-radar", "mlat-adsb", "smr-mlat", "all")
FILLS = ("hold", "predict")  # correlate: empty slots hold the previous one or take the tracker's prediction
TABLE_MODES = ("auto", "xlsx", "parquet")  # correlate: where the slot and lag tables go
REFERENCES = ("adsb", "track")  # quality: what radar accuracy is measured against
SMOOTHERS = ("rts", "imm")  # track: the backward pass
METHODS = ("exact", "one-block", "blocks", "midpoint")  # conflicts: how PC is computed
# a declared 1-sigma ADS-B error per axis below 0.5 m or above 20 km is no receiver's (the measurement
# model's adsb_sigma_m and the commands' --adsb-sigma)
ADSB_SIGMA_RANGE_M = (0.5, 20000.0)


def software_version() -> str:
    """The installed msdc version, or "unknown" when run from a checkout."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("msdc")
    except PackageNotFoundError:
        return "unknown"
