"""Radar/ADS-B correlation pipeline: pure functions over DataFrames, with a thin CLI."""
