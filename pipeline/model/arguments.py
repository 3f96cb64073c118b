"""Checks of library arguments shared by every step: one rule and one wording for a number of seconds,
metres or nautical miles, so that each call names the argument, the value and what is wanted."""

from __future__ import annotations

import math
from numbers import Real


def finite_number(name: str, value: object, unit: str = "seconds", *, above: float | None = 0.0,
                  at_least: float | None = None, at_least_name: str = "") -> float:
    """``value`` as a float: TypeError naming ``name`` when it is not a real number (a bool is not),
    ValueError when it is not finite, not above ``above`` (None: no such bound) or below ``at_least``
    (called ``at_least_name`` in the message, e.g. "step_s")."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{name} {value!r}: must be a number of {unit}, not {type(value).__name__}")
    v = float(value)
    if not (math.isfinite(v) and (above is None or v > above) and (at_least is None or v >= at_least)):
        bounds = [f"> {above:g}"] if above is not None else []
        if at_least is not None:
            bounds.append(f">= {at_least_name} ({at_least:g})" if at_least_name else f">= {at_least:g}")
        wanted = f"a finite number of {unit} {' and '.join(bounds)}".rstrip()
        raise ValueError(f"{name} {value!r}: must be {wanted}")
    return v
