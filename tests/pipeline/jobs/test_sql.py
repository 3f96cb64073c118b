"""msdc sql: DuckDB over a dataset, a view per category with the partition keys; counts per category and
sensor worked out from the fixtures' truth; the table, CSV and Parquet outputs; bad queries and folders."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from dataset_data import ADSB, DAY, FIX, RADAR

from msdc.pipeline.cli import main

pytest.importorskip("duckdb", reason="msdc sql needs DuckDB (pip install 'msdc[dataset]')")

TRUTH = json.loads((FIX / "truth.json").read_text())
COUNTS = ("SELECT category, sensor, date, count(*) AS n FROM cat048 GROUP BY ALL "
          "UNION ALL SELECT category, sensor, date, count(*) FROM cat021 GROUP BY ALL ORDER BY category")


def expected() -> pd.DataFrame:
    """The records per category and sensor the simulator wrote (truth.json), all on the fixtures' day."""
    r, a = TRUTH["radar"], TRUTH["adsb"]
    return pd.DataFrame({"category": [21, 48], "sensor": [f"{a['sac']}_{a['sic']}", f"{r['sac']}_{r['sic']}"],
                         "date": [DAY, DAY], "n": [a["rows"], r["rows"]]})


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("sql") / "ds"
    assert main(["ingest", str(RADAR), str(ADSB), "--dataset", str(root), "--date", DAY]) == 0
    return root


def test_counts_per_category_and_sensor_on_the_terminal(dataset, capsys):
    capsys.readouterr()
    assert main(["sql", "--dataset", str(dataset), COUNTS]) == 0
    lines = capsys.readouterr().out.split("\n")
    assert lines[0].split() == ["category", "sensor", "date", "n"]
    want = expected()
    assert [line.split() for line in lines[1:3]] == [[str(v) for v in row] for row in want.itertuples(
        index=False)]


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_written_to_csv_or_parquet(dataset, tmp_path, capsys, suffix):
    out = tmp_path / f"counts{suffix}"
    assert main(["sql", "--dataset", str(dataset), COUNTS, "-o", str(out)]) == 0
    assert f"2 row(s) -> {out}" in capsys.readouterr().out
    got = pd.read_csv(out) if suffix == ".csv" else pd.read_parquet(out)
    got["date"] = got["date"].astype(str)
    pd.testing.assert_frame_equal(got, expected(), check_dtype=False)


def test_reports_per_hour_equal_asterix_read(dataset):
    """The radar's plots per UTC hour through DuckDB, against asterix.read's timestamps of the file."""
    import msdc.asterix as asterix

    q = "SELECT hour(timestamp) AS h, count(*) AS n FROM cat048 WHERE sensor = '25_201' GROUP BY h ORDER BY h"
    out = dataset.parent / "h.csv"
    assert main(["sql", "--dataset", str(dataset), q, "-o", str(out)]) == 0
    got = pd.read_csv(out)
    ts = asterix.read(RADAR, date=DAY).frames[48]["timestamp"]
    want = ts.dt.hour.value_counts().sort_index()
    assert got["h"].tolist() == want.index.tolist() and got["n"].tolist() == want.tolist()
    assert got["n"].sum() == TRUTH["radar"]["rows"]


def test_a_csv_follows_every_csv_outputs_rules(dataset, tmp_path):
    """Formula-like text behind an apostrophe and times as ISO 8601 UTC to the microsecond with a Z
    (guide/index.md, "Outputs"), in every batch; a query of no rows writes the header alone."""
    import msdc.asterix as asterix

    out = tmp_path / "rules.csv"
    q = ("SELECT '=HYPERLINK(1)' AS x, timestamp FROM cat048 WHERE sensor = '25_201' ORDER BY timestamp "
         "LIMIT 3")
    assert main(["sql", "--dataset", str(dataset), q, "-o", str(out)]) == 0
    first = asterix.read(RADAR, date=DAY).frames[48]["timestamp"].sort_values().iloc[:3]
    lines = out.read_text().splitlines()
    assert lines[0] == "x,timestamp"
    assert lines[1:] == [f"'=HYPERLINK(1),{t:%Y-%m-%dT%H:%M:%S.%f}Z" for t in first]
    empty = tmp_path / "empty.csv"
    assert main(["sql", "--dataset", str(dataset), "SELECT callsign FROM cat048 WHERE false", "-o",
                 str(empty)]) == 0
    assert empty.read_text() == "callsign\n"


def test_a_csvs_lists_and_structs_are_written_as_the_terminal_shows_them(dataset, tmp_path, capsys):
    """A LIST column was written in numpy's form ("['AXM123' 'MAS136' ...]"); now as DuckDB's text of it,
    as the terminal's table shows it. The call signs by hand: the fixture's five radar aircraft."""
    truth = json.loads((FIX / "truth.json").read_text())
    names = sorted({a["callsign"] for a in truth["aircraft"]})
    out = tmp_path / "lists.csv"
    q = ("SELECT list(DISTINCT callsign ORDER BY callsign) AS cs, {'n': 1, 'v': [1, 2]} AS st "
         "FROM cat048 WHERE sensor = '25_201'")
    assert main(["sql", "--dataset", str(dataset), q, "-o", str(out)]) == 0
    assert out.read_text().splitlines() == ["cs,st", f'"[{", ".join(names)}]","{{\'n\': 1, \'v\': [1, 2]}}"']


def test_a_csv_of_many_batches_holds_every_row_once(dataset, tmp_path, monkeypatch):
    import msdc.pipeline.jobs.sql as sql

    monkeypatch.setattr(sql, "CSV_BATCH_ROWS", 1000)
    out = tmp_path / "all.csv"
    q = "SELECT time_of_day FROM cat048 ORDER BY time_of_day"
    assert main(["sql", "--dataset", str(dataset), q, "-o", str(out)]) == 0
    got = pd.read_csv(out)
    assert len(got) == TRUTH["radar"]["rows"] and got["time_of_day"].is_monotonic_increasing


@pytest.mark.parametrize("args,says", [
    (["SELECT * FROM cat099"], "cat099"),
    (["SELEKT 1"], "the query failed"),
    ([""], "no query given"),
])
def test_a_bad_query_exits_2_with_a_message(dataset, tmp_path, capsys, args, says):
    out = tmp_path / "x.csv"
    assert main(["sql", "--dataset", str(dataset), *args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # nothing written, nothing staged left


def test_a_folder_that_is_no_dataset(tmp_path, capsys):
    assert main(["sql", "--dataset", str(tmp_path), "SELECT 1"]) == 2
    assert "not an msdc dataset" in capsys.readouterr().err


def _copy(dataset: Path, tmp_path: Path) -> tuple[Path, Path]:
    """A copy of the dataset to damage, and its CAT048 part (the radar's one part, found by its folder)."""
    import shutil

    root = tmp_path / "copy"
    shutil.copytree(dataset, root)
    (part,) = root.glob("date=*/category=048/sensor=*/part-*.parquet")
    return root, part


def _said_damaged(capsys, root: Path, part: Path, why: str) -> None:
    err = capsys.readouterr().err
    assert err.startswith(f"msdc sql: --dataset {root}: 1 damaged part(s) cannot be read as ingest wrote "
                          "them, the query was not run: "
                          f"{part.relative_to(root).as_posix()} ({TRUTH['radar']['rows']:,} CAT048 records "
                          f"of {RADAR.name}): {why}")
    assert "Traceback" not in err and err.count("\n") == 1


@pytest.mark.parametrize("at_share", [0.25, 0.5, 0.75])
def test_a_part_with_zeros_over_its_middle_is_refused_naming_it(dataset, tmp_path, capsys, at_share):
    """16 zero bytes written over a part (its size unchanged) gave other values, or a bare decompression
    error, depending on where they fell: now the query is refused, the part named with the CRC-32s."""
    import zlib

    root, part = _copy(dataset, tmp_path)
    data = bytearray(part.read_bytes())
    at = int(len(data) * at_share)
    data[at:at + 16] = bytes(16)
    part.write_bytes(bytes(data))
    inputs = json.loads((root / "manifest.json").read_text())["inputs"]
    listed = next(p for rec in inputs for p in rec["parts"] if p["path"] == part.relative_to(root).as_posix())
    out = tmp_path / "n.csv"
    assert main(["sql", "--dataset", str(root), "SELECT count(*), sum(time_of_day) FROM cat048", "-o",
                 str(out)]) == 2
    _said_damaged(capsys, root, part, f"its bytes are not those ingest wrote (CRC-32 "
                                      f"{zlib.crc32(data):08x} where the manifest records {listed['crc32']})")
    assert not out.exists()


def test_a_part_changed_into_another_valid_parquet_file_is_refused(dataset, tmp_path, capsys):
    """The silent case: the part rewritten whole, every row kept, one time of day changed (DuckDB reads it
    as valid, and nothing but the recorded checksum tells it from the part ingest wrote)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    root, part = _copy(dataset, tmp_path)
    table = pq.read_table(part)
    times = table.column("time_of_day").to_pylist()
    table = table.set_column(table.schema.get_field_index("time_of_day"), "time_of_day",
                             pa.array([times[0] + 1.0, *times[1:]], table.schema.field("time_of_day").type))
    pq.write_table(table, part)
    assert main(["sql", "--dataset", str(root), "SELECT count(*) FROM cat048"]) == 2
    err = capsys.readouterr().err
    assert "1 damaged part(s) cannot be read as ingest wrote them, the query was not run" in err
    assert part.name in err and "Traceback" not in err


def test_a_truncated_or_missing_part_is_refused(dataset, tmp_path, capsys):
    root, part = _copy(dataset, tmp_path)
    size = part.stat().st_size
    with open(part, "r+b") as fh:
        fh.truncate(size - 100)
    assert main(["sql", "--dataset", str(root), "SELECT count(*) FROM cat048"]) == 2
    _said_damaged(capsys, root, part, f"it holds {size - 100:,} bytes where ingest wrote {size:,}")
    part.unlink()
    assert main(["sql", "--dataset", str(root), "SELECT count(*) FROM cat048"]) == 2
    _said_damaged(capsys, root, part, "it is missing")


def test_a_query_of_other_views_runs_beside_a_damaged_part(dataset, tmp_path, capsys):
    """Only the parts of the views the query names are checked: the ADS-B count is right and said."""
    root, part = _copy(dataset, tmp_path)
    part.write_bytes(bytes(part.stat().st_size))
    assert main(["sql", "--dataset", str(root), "SELECT count(*) AS n FROM cat021"]) == 0
    captured = capsys.readouterr()
    assert captured.out.split() == ["n", str(TRUTH["adsb"]["rows"])] and captured.err == ""


def test_a_dataset_ingested_before_part_checksums_is_read_with_a_warning(dataset, tmp_path, capsys):
    """Parts listed without size and CRC-32 (an older msdc's manifest) are read as before, the count right,
    and a warning says they were not checked."""
    root, _ = _copy(dataset, tmp_path)
    doc = json.loads((root / "manifest.json").read_text())
    for rec in doc["inputs"]:
        for p in rec["parts"]:
            del p["size_bytes"], p["crc32"]
    (root / "manifest.json").write_text(json.dumps(doc))
    assert main(["sql", "--dataset", str(root), "SELECT count(*) AS n FROM cat048"]) == 0
    captured = capsys.readouterr()
    assert captured.out.split() == ["n", str(TRUTH["radar"]["rows"])]
    assert captured.err == ("msdc sql: warning: 1 part(s) the query may read carry no checksum (ingested "
                            "before msdc recorded them): read unchecked, a damaged one would go unnoticed\n")


@pytest.mark.parametrize("key,value,says", [
    ("crc32", 12345, "crc32 12345 is no CRC-32 (8 hex digits)"),
    ("crc32", "xyz", "crc32 'xyz' is no CRC-32 (8 hex digits)"),
    ("size_bytes", -1, "size_bytes -1 is no count"),
])
def test_a_manifest_with_a_bad_checksum_record_exits_2_naming_it(dataset, tmp_path, capsys, key, value, says):
    root, part = _copy(dataset, tmp_path)
    doc = json.loads((root / "manifest.json").read_text())
    for rec in doc["inputs"]:
        for p in rec["parts"]:
            if p["category"] == 48:
                p[key] = value
    (root / "manifest.json").write_text(json.dumps(doc))
    assert main(["sql", "--dataset", str(root), "SELECT count(*) FROM cat048"]) == 2
    err = capsys.readouterr().err
    assert f"part '{part.relative_to(root).as_posix()}': {says}" in err and "Traceback" not in err
