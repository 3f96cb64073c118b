"""Slot and lag tables as Parquet beside the workbook (``--tables``, pipeline.report.tables): the files
hold what the workbook's sheets would have held, the workbook names them, the charts read an excerpt, and
a failed run leaves nothing behind."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from openpyxl import load_workbook

from msdc.pipeline.jobs import correlate
from msdc.pipeline.report import tables as tables_mod
from msdc.pipeline.report.headers import column_name

# one worker runs the module: the correlation and its workbooks made once, not on each worker
pytestmark = pytest.mark.xdist_group("tables")

FIX = Path(__file__).resolve().parents[3] / "fixtures"
EXCEL_EPOCH = dt.datetime(1899, 12, 30)


@pytest.fixture(scope="module")
def result():
    options = correlate.CorrelateOptions(inputs=(str(FIX / "radar.ast"), str(FIX / "adsb.ast")),
                                    sensors=str(FIX / "sensors.toml"), all_aircraft=True,
                                    date=dt.date(2019, 3, 1))
    return correlate.correlate_job(options)


@pytest.fixture(scope="module")
def written_xlsx(result, tmp_path_factory) -> dict[str, Path]:
    """The run written once with --tables xlsx, to r.xlsx in a folder of its own (the tests only read it)."""
    return _write(result, tmp_path_factory.mktemp("xlsx") / "r.xlsx", "xlsx")


@pytest.fixture(scope="module")
def written_parquet(result, tmp_path_factory) -> dict[str, Path]:
    """The run written once with --tables parquet, to r.xlsx in a folder of its own (the tests only read
    it)."""
    return _write(result, tmp_path_factory.mktemp("parquet") / "r.xlsx", "parquet")


def _write(result, out: Path, tables: str) -> dict[str, Path]:
    options = correlate.CorrelateOptions(**{**result.options.__dict__, "output": str(out), "tables": tables})
    checked = correlate.validate(options)
    return correlate.write_correlation(correlate.CorrelateResult(options, checked, result.run,
                                                                 result.measurements, result.loaded))


def _sheet(ws) -> dict[str, list]:
    """A data sheet's columns (snake_case name of the header -> cell values): rows until the first empty one
    (the note follows)."""
    rows = list(ws.iter_rows(values_only=True))
    header = [column_name(h) for h in rows[0]]
    body = []
    for row in rows[1:]:
        if all(v is None for v in row):
            break
        body.append(list(row)[:len(header)])
    return {h: [r[j] for r in body] for j, h in enumerate(header)}


def _same(sheet_values, parquet_values, name):
    for a, b in zip(sheet_values, parquet_values, strict=True):
        if b is None or (isinstance(b, float) and math.isnan(b)) or b is pd.NA:
            assert a is None, (name, a, b)
        elif isinstance(b, pd.Timestamp):
            assert abs(pd.Timestamp(a) - b.tz_convert("UTC").tz_localize(None)) < pd.Timedelta(milliseconds=1)
        elif isinstance(b, float):
            assert a == pytest.approx(b, rel=1e-12, abs=1e-12), name
        else:
            assert a == b, (name, a, b)


def test_parquet_equals_the_workbook_sheets(written_xlsx, written_parquet):
    xlsx, pq = written_xlsx, written_parquet
    assert set(xlsx) == {"report", "figure"}  # xlsx: no Parquet
    assert not list(xlsx["report"].parent.glob("*.parquet"))
    folder = pq["report"].parent
    assert pq["table slots"] == folder / "r_slots.parquet"
    assert pq["table correlation"] == folder / "r_correlation.parquet"
    wb = load_workbook(xlsx["report"])
    for sheet, path in (("Slots", pq["table slots"]), ("Correlation", pq["table correlation"])):
        table = pd.read_parquet(path)
        shown = _sheet(wb[sheet])
        assert len(table) == len(shown["window"]) > 0
        assert set(shown) == set(table.columns)  # the sensor pair too: window numbers restart per pair
        for column, values in shown.items():
            _same(values, table[column].astype(object).tolist(), column)


def test_parquet_tables_against_the_run(result, written_parquet):
    """Independent of the writers: one slot row per slot of each window, 2N - 1 lags per window at 10 s a
    slot, the sensors of each window as its summary names them."""
    slots, lags = (pd.read_parquet(written_parquet[f"table {n}"]) for n in ("slots", "correlation"))
    windows = result.run.windows
    assert len(slots) == sum(w.summary["slots"] for w in windows)
    assert len(lags) == sum(2 * w.summary["slots"] - 1 for w in windows)
    np.testing.assert_allclose(lags["lag_s"], 10.0 * lags["lag"])
    start = 0
    for w in windows:
        n = w.summary["slots"]
        part = slots.iloc[start:start + n]
        assert (part["callsign"] == w.summary["callsign"]).all()
        assert (part["radar_sensor"] == w.summary["radar_sensor"]).all()
        assert (part["reference_sensor"] == w.summary["reference_sensor"]).all()
        assert part["slot"].tolist() == list(range(n))
        first = pd.Timestamp("2019-03-01", tz="UTC") + pd.to_timedelta(w.summary["start_tod"], unit="s")
        assert abs(part["time_utc"].iloc[0] - first) < pd.Timedelta(microseconds=1)
        assert (part["time_utc"].diff().dropna() == pd.Timedelta(seconds=10)).all()
        start += n


def test_workbook_names_the_files_and_charts_read_the_excerpt(written_parquet):
    written = written_parquet
    wb = load_workbook(written["report"])
    for sheet, name, data in (("Slots", "slots", "Slot chart data"), ("Correlation", "correlation",
                                                                      "Lag chart data")):
        table = pd.read_parquet(written[f"table {name}"])
        ws = wb[sheet]
        title = ws["A1"].value
        assert f"r_{name}.parquet" in title and f"{len(table):,} rows" in title
        assert "--tables parquet" in ws["A2"].value
        listed = [ws.cell(row=r, column=1).value for r in range(5, 5 + len(table.columns))]
        assert listed == list(table.columns)
        assert data in wb.sheetnames
    # each slot chart's series point at the excerpt rows of its own window
    excerpt = _sheet(wb["Slot chart data"])
    charts = wb["Slot charts"]._charts
    assert charts
    for chart in charts:
        ref = chart.series[0].yVal.numRef.f  # 'Slot chart data'!$E$2:$E$40
        assert ref.startswith("'Slot chart data'!")
        rows = [int(part.split("$")[-1]) for part in ref.split("!")[1].split(":")]
        callsigns = set(excerpt["callsign"][rows[0] - 2:rows[1] - 1])
        assert len(callsigns) == 1
        assert callsigns.pop() in chart.title.tx.rich.p[0].r[0].t
    lag_charts = wb["Lag charts"]._charts
    assert lag_charts and all(c.series[0].xVal.numRef.f.startswith("'Lag chart data'!") for c in lag_charts)


def test_auto_threshold(result, tmp_path, monkeypatch):
    rows = sum(len(w.slots) for w in result.run.windows)
    assert rows <= tables_mod.AUTO_MAX_ROWS  # the fixtures stay in the workbook
    assert not {k for k in _write(result, tmp_path / "a.xlsx", "auto") if k.startswith("table")}
    monkeypatch.setattr(tables_mod, "AUTO_MAX_ROWS", rows)  # lags (2N - 1 a window) go, slots stay
    written = _write(result, tmp_path / "b.xlsx", "auto")
    assert {k for k in written if k.startswith("table")} == {"table correlation"}
    wb = load_workbook(written["report"])
    assert "more than" in wb["Correlation"]["A2"].value and "--tables auto" in wb["Correlation"]["A2"].value
    assert len(_sheet(wb["Slots"])["window"]) == rows


def test_failure_leaves_nothing(result, tmp_path, monkeypatch):
    """The workbook fails after the Parquet files and the figure were written: none of them stays, a file
    that was there before does."""
    import msdc.pipeline.report.excel as excel

    real = excel.save

    def disk_full(wb, path):
        assert (path.parent / "f_slots.parquet").exists() and (path.parent / "f_tracks.png").exists()
        real(wb, path)
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(excel, "save", disk_full)
    (tmp_path / "kept.txt").write_text("was here")
    with pytest.raises(OSError):
        _write(result, tmp_path / "f.xlsx", "parquet")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.txt"]


def test_track_map_of_many_slots_draws_lines_only(result, tmp_path, monkeypatch):
    """Past MAX_MARKED_SLOTS the map keeps one line per sensor kind and says markers were left out."""
    from matplotlib.figure import Figure

    import msdc.pipeline.report.figures as figures

    drawn = {}
    monkeypatch.setattr(figures, "MAX_MARKED_SLOTS", 10)
    monkeypatch.setattr(figures, "save_png",
                        lambda fig, path, *level: drawn.setdefault("fig", fig) and Path(path))
    figures.track_figure(result.run, tmp_path / "t.png", result.checked.sensors)
    fig: Figure = drawn["fig"]
    ax = fig.axes[0]
    assert "lines only" in ax.get_title()
    tracks = [line for line in ax.lines if line.get_linestyle() == "-" and len(line.get_xdata()) > 10]
    assert len(tracks) == 2  # radar and ADS-B, every window in one line each
    assert not [line for line in ax.lines if line.get_marker() == "o" and len(line.get_xdata()) > 10]


def test_track_map_legend_lies_inside_the_axes(result, tmp_path, monkeypatch):
    """The map's legend ("best" place) is drawn inside the axes, so leaving it out of the constrained layout
    cannot move anything."""
    import msdc.pipeline.report.figures as figures

    drawn = {}
    real = figures.save_png
    monkeypatch.setattr(figures, "save_png", lambda fig, path, *level: drawn.setdefault("fig", fig)
                        and real(fig, path, *level))
    figures.track_figure(result.run, tmp_path / "t.png", result.checked.sensors)
    ax = drawn["fig"].axes[0]
    legend, box = ax.get_legend().get_window_extent(), ax.get_window_extent()
    assert box.x0 <= legend.x0 < legend.x1 <= box.x1 and box.y0 <= legend.y0 < legend.y1 <= box.y1


def test_track_map_png_has_the_pixels_of_the_default_encoding(result, tmp_path, monkeypatch):
    """The map is encoded at a faster zlib level than Pillow's default: the same pixels, decoded."""
    from matplotlib.image import imread

    import msdc.pipeline.report.figures as figures

    fast = figures.track_figure(result.run, tmp_path / "fast.png", result.checked.sensors)
    monkeypatch.setattr(figures, "TRACK_PNG_COMPRESS_LEVEL", None)
    default = figures.track_figure(result.run, tmp_path / "default.png", result.checked.sensors)
    a, b = (imread(p) for p in (fast, default))
    assert a.shape == b.shape and (a == b).all()


def test_farthest_point_is_the_largest_geodesic_distance():
    """farthest_m equals the largest WGS-84 distance measured to every point (pyproj), including points
    that all lie near one range in every direction, where the sphere and the ellipsoid rank them apart."""
    from pyproj import Geod

    from msdc.pipeline.report.figures import farthest_m

    geod, rng = Geod(ellps="WGS84"), np.random.default_rng(7)
    site_lat, site_lon = 52.0, 4.5
    for ranges_m in (rng.uniform(0, 400e3, 3000), 300e3 + rng.uniform(-500, 500, 3000)):
        azimuths = rng.uniform(0, 360, ranges_m.size)
        lons, lats, _ = geod.fwd(np.full(ranges_m.size, site_lon), np.full(ranges_m.size, site_lat), azimuths,
                                 ranges_m)
        _, _, every_m = geod.inv(np.full(lats.size, site_lon), np.full(lats.size, site_lat), lons, lats)
        assert farthest_m(geod, site_lat, site_lon, lats, lons) == float(np.max(every_m))
    assert farthest_m(geod, site_lat, site_lon, np.array([]), np.array([])) == 0.0


@pytest.mark.parametrize("tables", ["xlsx", "parquet"])
def test_chart_series_read_the_columns_they_name(request, tables):
    """Every chart series' x and y references point at the data sheet's columns of that name (lag and a
    coefficient; slot time and a position), rows of the charted window."""
    from openpyxl.utils import column_index_from_string

    wb = load_workbook(request.getfixturevalue(f"written_{tables}")["report"])
    wanted = {"Lag charts": ("lag", {"NCC lat": "ncc_lat", "NCC lon": "ncc_lon", "Pearson lat": "pearson_lat",
                                     "Pearson lon": "pearson_lon"}),
              "Slot charts": ("time_utc", None)}
    for sheet, (x_name, y_names) in wanted.items():
        charts = wb[sheet]._charts
        assert charts
        for chart in charts:
            for series in chart.series:
                refs = {}
                for axis, ref in (("x", series.xVal.numRef.f), ("y", series.yVal.numRef.f)):
                    data, cells = ref.rsplit("!", 1)
                    ws = wb[data.strip("'")]
                    col = column_index_from_string(cells.split("$")[1])
                    refs[axis] = column_name(ws.cell(row=1, column=col).value)
                assert refs["x"] == x_name, (sheet, refs)
                title = series.tx.strRef.f if series.tx.strRef is not None else series.tx.v
                if y_names is not None:
                    assert refs["y"] == y_names[title], (title, refs)
                else:
                    axis = "lat" if "latitude" in chart.title.tx.rich.p[0].r[0].t else "lon"
                    assert refs["y"] == f"{'radar' if title == 'Radar' else 'adsb'}_{axis}", (title, refs)


@pytest.mark.parametrize("name", ["slots", "correlation"])
def test_parquet_written_in_batches_equals_the_whole_table(result, tmp_path, name):
    """A long table is built and written a few windows at a time (bounded memory): the file holds the same
    columns, types, pandas metadata and rows as the whole table written at once."""
    import pyarrow.parquet as pq

    run = result.run
    parts = tables_mod._batches(run, name, 300)
    length = [len(w.slots if name == "slots" else w.lags) for w in run.windows]
    sizes = [[length[i] for i in p] for p in parts]
    assert len(parts) > 2 and [i for p in parts for i in p] == list(range(len(run.windows)))
    assert all(sum(s) <= 300 or len(s) == 1 for s in sizes)  # whole windows, one alone when longer
    whole = tables_mod.write_parquet(tables_mod.TABLE_BUILDERS[name](run), tmp_path / "whole.parquet")
    rows, schema = tables_mod.write_table_parquet(run, name, tmp_path / "batched.parquet", batch_rows=300)
    a, b = pq.read_table(whole), pq.read_table(tmp_path / "batched.parquet")
    assert pq.ParquetFile(tmp_path / "batched.parquet").metadata.num_row_groups == len(parts)
    assert rows == a.num_rows == b.num_rows == sum(map(sum, sizes))
    assert b.equals(a, check_metadata=True) and schema.equals(a.schema, check_metadata=True)
    pd.testing.assert_frame_equal(b.to_pandas(), a.to_pandas())


def test_lag_frame_is_in_increasing_lag_whatever_the_order_given():
    """A window's lag table in increasing lag, ties kept in the order given; one already in order is used
    as it is (no copy)."""
    from msdc.pipeline.correlate.results import WindowResult

    shuffled = pd.DataFrame({"lag": [1, -1, 0, 1], "ncc_lat": [0.1, 0.2, 0.3, 0.4]})
    got = tables_mod.lag_frame(WindowResult({}, pd.DataFrame(), shuffled))
    assert got["lag"].tolist() == [-1, 0, 1, 1] and got["ncc_lat"].tolist() == [0.2, 0.3, 0.1, 0.4]
    ordered = pd.DataFrame({"lag": [-2, 0, 0, 3], "ncc_lat": [1.0, 2.0, 3.0, 4.0]})
    assert tables_mod.lag_frame(WindowResult({}, pd.DataFrame(), ordered)) is ordered
    no_lag = pd.DataFrame({"ncc_lat": [1.0]})
    assert tables_mod.lag_frame(WindowResult({}, pd.DataFrame(), no_lag)) is no_lag


def test_charts_sharing_their_parts_come_out_alike_and_as_described(result, written_xlsx, tmp_path):
    """Chart parts made once and shared (axis titles, lines, markers) give the same chart XML in a second
    workbook written by this process, and each lag chart's series look as its sheet says: NCC solid,
    Pearson dashed; latitude blue (1F77B4), longitude green (2CA02C)."""
    import re
    import zipfile

    first, second = written_xlsx, _write(result, tmp_path / "r.xlsx", "xlsx")  # the second here
    a, b = zipfile.ZipFile(first["report"]), zipfile.ZipFile(second["report"])
    charts = [n for n in a.namelist() if n.startswith("xl/charts/chart")]
    assert charts and all(a.read(n) == b.read(n) for n in charts)
    xml = a.read("xl/charts/chart1.xml").decode()
    series = re.findall(r"<ser>.*?</ser>", xml, flags=re.S)
    looks = [(re.search(r'<a:srgbClr val="(\w+)"', s).group(1), 'prstDash val="dash"' in s) for s in series]
    assert looks == [("1F77B4", False), ("2CA02C", False), ("1F77B4", True), ("2CA02C", True)]
    assert all('<symbol val="none"/>' in s for s in series)
