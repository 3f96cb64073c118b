"""The data model: sensors, geodesy, measurements, deduplication and loading recordings."""
