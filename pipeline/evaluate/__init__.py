"""Evaluation against the surveillance standards: statistics that decide (intervals, verdicts) and the
standards' requirements as data (presets)."""
