"""Sensor data quality: update intervals, gaps, jumps, filters and radar accuracy."""
