"""The sensor file's limits and odd encodings (issue 27, items 8 and 9): a UTF-8 byte order mark read, deep
nesting and oversized files or names refused with the reason, and a name never copied per report."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.cli import main
from msdc.pipeline.model.sensors import read_sensors, sensor_sites

FIX = Path(__file__).resolve().parents[3] / "fixtures"
SENSORS = FIX / "sensors.toml"
ONE_MIB = 1_048_576  # the documented file limit (docs/guide/sensors.md)


def written(tmp_path: Path, data: bytes, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def test_a_byte_order_mark_is_read_as_windows_notepad_writes_it(tmp_path):
    """Notepad's UTF-8 starts with EF BB BF; tomllib refused it as 'Invalid statement (at line 1, column
    1)'. The same table as without it."""
    with_bom = written(tmp_path, b"\xef\xbb\xbf" + SENSORS.read_bytes())
    table = read_sensors(with_bom)
    pd.testing.assert_frame_equal(table, read_sensors(SENSORS))
    assert table["name"].astype(str).tolist() == ["KLIA MSSR"]


@pytest.mark.parametrize("nesting", ["x = " + "[" * 5000 + "]" * 5000,
                                     "x = " + "{a = " * 3000 + "1" + "}" * 3000],
                         ids=["arrays", "inline tables"])
def test_deep_nesting_is_refused_with_the_reason_not_a_recursion_error(tmp_path, nesting):
    path = written(tmp_path, SENSORS.read_bytes() + nesting.encode() + b"\n")
    with pytest.raises(ValueError, match="nested too deeply") as info:
        read_sensors(path)
    assert str(info.value).startswith(f"{path}: ")


def test_a_deeply_nested_sensor_file_ends_the_command_in_one_line(tmp_path, capsys):
    path = written(tmp_path, SENSORS.read_bytes() + b"x = " + b"[" * 5000 + b"]" * 5000 + b"\n")
    assert main(["track", str(FIX / "radar.ast"), "--sensors", str(path), "--all", "--json",
                 str(tmp_path / "t.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nested too deeply" in err and "Traceback" not in err
    assert not (tmp_path / "t.json").exists()


def test_the_file_size_limit_is_one_mebibyte(tmp_path):
    """A file of exactly 1 MiB (the fixture's entry and a comment) is read; one byte more is refused,
    naming the limit, before it is parsed."""
    entry = SENSORS.read_bytes()
    pad = ONE_MIB - len(entry) - 2
    at_limit = written(tmp_path, entry + b"#" + b"x" * pad + b"\n", "limit.toml")
    assert at_limit.stat().st_size == ONE_MIB
    assert len(read_sensors(at_limit)) == 1
    over = written(tmp_path, entry + b"#" + b"x" * (pad + 1) + b"\n", "over.toml")
    with pytest.raises(ValueError, match=f"{over}: larger than 1,048,576 bytes, the limit of a sensor file"):
        read_sensors(over)


def test_a_name_may_have_up_to_100_characters(tmp_path):
    text = SENSORS.read_text()
    hundred = written(tmp_path, text.replace("KLIA MSSR", "N" * 100).encode(), "a.toml")
    assert read_sensors(hundred)["name"].astype(str).tolist() == ["N" * 100]
    longer = written(tmp_path, text.replace("KLIA MSSR", "N" * 101).encode(), "b.toml")
    with pytest.raises(ValueError, match=r"entry 1 \(SAC 25 SIC 201\): name is 101 characters long; a name "
                       "may have up to 100"):
        read_sensors(longer)


def test_a_name_is_never_copied_per_report():
    """Each report's site row (sensor_sites) for 2,000 reports of a radar with a 0.5 MB name (built as a
    table, past the file limits): the name stays one categorical value; a copy per report would take
    1 GB."""
    name = "R" * 500_000
    sensors = pd.DataFrame({"name": [name, "other"], "sac": [25, 1], "sic": [201, 2], "latitude": [2.7, 1.0],
                            "longitude": [101.7, 1.0], "altitude_m": [40.0, 0.0]})
    reports = pd.DataFrame({"sac": np.full(2000, 25), "sic": np.full(2000, 201)})
    tracemalloc.start()
    try:
        sites = sensor_sites(reports, sensors)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 10_000_000, peak
    assert isinstance(sites["name"].dtype, pd.CategoricalDtype) and (sites["name"] == name).all()
    assert isinstance(read_sensors(SENSORS)["name"].dtype, pd.CategoricalDtype)
