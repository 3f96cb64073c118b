"""Fixtures shared by the evaluate tests."""

from __future__ import annotations

import pytest

from msdc.pipeline.evaluate import ranks

# (values read whole at most, bins a range is cut into): the module's own, then small enough for many passes
CUTS = [(ranks.COLLECT_VALUES, ranks.BINS), (40, 4), (3, 2)]


@pytest.fixture(params=CUTS, ids=["as-built", "small", "bisection"])
def cuts(request, monkeypatch):
    """ranks' limits as built, then small ones that make order statistics take many passes."""
    monkeypatch.setattr(ranks, "COLLECT_VALUES", request.param[0])
    monkeypatch.setattr(ranks, "BINS", request.param[1])
    return request.param
