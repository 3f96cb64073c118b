"""Imported by the ingest pool's forkserver only (ingest.POOL_PRELOAD): a tiny recording, a CAT048 and a
CAT021 data block, checked once there, so that numba's compiled kernels are loaded (from its cache) once,
in the forkserver, and every pool process forked from it starts with them (each loaded them itself, about
1 s of CPU, before). Imported anywhere else (the forkserver's environment lacks WARM_ENV), it does nothing:
with a cold numba cache the warm-up compiles the decoder, about 20 s."""

from __future__ import annotations

import os

WARM_ENV = "MSDC_INGEST_FORKSERVER"  # set only in the ingest pool's forkserver (jobs.ingest._forkserver)


def warm() -> None:
    """Check a two-block recording as an input is checked (asterix.verdict.sniff), then delete it."""
    import os
    import tempfile

    import pandas as pd

    from msdc.asterix.encode import encode_frame
    from msdc.asterix.verdict import sniff

    plots = pd.DataFrame({"sac": [20, 20], "sic": [1, 1], "time_of_day": [100.0, 101.0]})
    reports = pd.DataFrame({"sac": [0, 0], "sic": [1, 1], "time_applicability_position": [100.0, 101.0],
                            "latitude": [40.0, 40.1], "longitude": [2.0, 2.1]})
    fd, path = tempfile.mkstemp(prefix="msdc-warm-", suffix=".ast")
    try:
        os.write(fd, encode_frame(48, plots) + encode_frame(21, reports))
        os.close(fd)
        sniff(path, None)
    finally:
        os.unlink(path)


if os.environ.get(WARM_ENV) == "1":
    try:
        warm()
    except Exception:  # noqa: BLE001,S110 - only a head start: each pool process loads the kernels it lacks
        pass
