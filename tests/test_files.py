"""The one JSON writer and the one CSV writer of every output (pipeline/report/files.py), and write errors
naming the file."""

from __future__ import annotations

import errno
import json
import math

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.report.files import named, write_json


def _strict(text: str):
    """json.loads refusing NaN and infinities (Python's own reader accepts them)."""
    def refuse(name: str):
        raise ValueError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_the_json_writer_is_strict_utf8_indented_and_writes_one_time_format(tmp_path):
    doc = {"nan": float("nan"), "inf": np.inf, "nat": pd.NaT, "na": pd.NA, "n": np.int64(3),
           "ok": np.bool_(True), "naive": pd.Timestamp("2019-03-01 10:00:00.123456789"),
           "aware": pd.Timestamp("2019-03-01 12:00:00", tz="Europe/Paris"),
           "whole": np.datetime64("2019-03-01T10:00:00"), "name": "Zürich ✈", "rows": [{"x": math.nan}]}
    path = write_json(doc, tmp_path / "o.json")
    text = path.read_bytes().decode("utf-8")
    assert _strict(text) == {"nan": None, "inf": None, "nat": None, "na": None, "n": 3, "ok": True,
                             "naive": "2019-03-01T10:00:00.123Z", "aware": "2019-03-01T11:00:00.000Z",
                             "whole": "2019-03-01T10:00:00.000Z", "name": "Zürich ✈", "rows": [{"x": None}]}
    assert text.startswith('{\n  "nan": null,') and text.endswith("}\n")


def test_a_write_error_without_a_file_name_is_given_the_output(tmp_path):
    with pytest.raises(OSError) as raised, named(tmp_path / "t.parquet"):
        raise OSError("Error writing bytes to file. Detail: [errno 28] No space left on device")
    assert raised.value.filename == str(tmp_path / "t.parquet") and raised.value.errno == errno.ENOSPC
    assert raised.value.strerror == "No space left on device"
    with pytest.raises(OSError) as raised, named(tmp_path / "t.parquet"):
        raise OSError(errno.EACCES, "Permission denied", "/elsewhere/x")  # names its file already: kept
    assert raised.value.filename == "/elsewhere/x"
