"""A Parquet dataset of decoded records, partitioned by UTC day, category and sensor (``msdc ingest``):
its layout, its manifest, the writer that commits parts atomically and the reader that lists them."""
