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
