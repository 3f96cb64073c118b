"""Radar/ADS-B correlation: overlap windows, slots, coefficients and their result types."""
