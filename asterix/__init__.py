"""ASTERIX decoding: containers, framing, edition tables, the record walker, typed frames, encoder."""
