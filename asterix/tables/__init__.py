"""Per-edition ASTERIX item tables (JSON data) and the loader."""
