"""msdc, the Multi-Sensor Data Correlator: ASTERIX decoding and surveillance-data analysis.

The repository root is the installed package ``msdc``: ``msdc.asterix`` decodes, ``msdc.pipeline`` analyses.
Its public face is small and loaded on first use, so ``import msdc`` costs nothing until a name is needed:
``msdc.read`` and ``msdc.iter_read`` decode recordings into frames, the ``*_job`` functions run the commands
(one for each command; their options classes are in ``msdc.pipeline.jobs.<command>``).
"""

from __future__ import annotations

import importlib

# name -> (module, attribute): resolved lazily by __getattr__ (PEP 562)
_PUBLIC = {
    "read": ("msdc.asterix", "read"),
    "iter_read": ("msdc.asterix", "iter_read"),
    "Recording": ("msdc.asterix", "Recording"),
    "encode": ("msdc.asterix.encode", "encode_frame"),
    "decode_job": ("msdc.pipeline.jobs.decode", "decode_job"),
    "stats_job": ("msdc.pipeline.jobs.stats", "stats_job"),
    "correlate_job": ("msdc.pipeline.jobs.correlate", "correlate_job"),
    "quality_job": ("msdc.pipeline.jobs.quality", "quality_job"),
    "track_job": ("msdc.pipeline.jobs.track", "track_job"),
    "conflict_job": ("msdc.pipeline.jobs.conflicts", "conflict_job"),
    "evaluate_job": ("msdc.pipeline.jobs.evaluate", "evaluate_job"),
    "ingest_job": ("msdc.pipeline.jobs.ingest", "ingest_job"),
    "sql_job": ("msdc.pipeline.jobs.sql", "sql_job"),
    "listen_job": ("msdc.pipeline.jobs.listen", "listen_job"),
    "replay_job": ("msdc.pipeline.jobs.replay", "replay_job"),
}

__all__ = sorted(_PUBLIC)


def __getattr__(name: str):
    """Import a public name's module when the name is first used."""
    try:
        module, attribute = _PUBLIC[name]
    except KeyError:
        raise AttributeError(f"module 'msdc' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
