"""How many examples a property test draws: the count written in the test under the full Hypothesis
profile (``pytest --hypothesis-profile=full``), a quarter of it (at least 5) under the default ``ci``
profile that every plain ``pytest`` run uses (tests/conftest.py registers both)."""

from __future__ import annotations

from hypothesis import settings

FULL_MAX_EXAMPLES = 100  # the full profile's max_examples: the scale on which tests write their counts


def examples(full: int) -> int:
    """``full`` scaled by the loaded profile (ci: 25 %), never below 5."""
    return max(5, round(full * settings.default.max_examples / FULL_MAX_EXAMPLES))
