"""msdc.pipeline.report.saving: a write-only workbook saved with its charts' XML built beforehand and its
images stored holds the same parts, byte for byte, as openpyxl's own save."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
from openpyxl import Workbook
from openpyxl.chart import Reference, ScatterChart, Series
from openpyxl.drawing.image import Image

from msdc.pipeline.report import saving


def _workbook(png: Path) -> Workbook:
    wb = Workbook(write_only=True)
    ws = wb.create_sheet("Data")
    for i in range(20):
        ws.append([i, i * i])
    chart = ScatterChart()
    chart.title = "squares"
    chart.series.append(Series(Reference(ws, min_col=2, min_row=1, max_row=20),
                               Reference(ws, min_col=1, min_row=1, max_row=20), title="y"))
    ws.add_chart(chart, "D2")
    pictures = wb.create_sheet("Picture")
    pictures.add_image(Image(str(png)), "A1")
    return wb


def test_saved_parts_are_openpyxls_with_the_image_stored(tmp_path):
    from matplotlib.image import imsave

    png = tmp_path / "noise.png"
    imsave(png, np.random.default_rng(1).integers(0, 255, (40, 60, 3), dtype=np.uint8))
    _workbook(png).save(tmp_path / "openpyxl.xlsx")
    ours = _workbook(png)
    saving.get_ready(ours)  # the charts' XML built before the save
    saving.save(ours, tmp_path / "ours.xlsx")
    a, b = zipfile.ZipFile(tmp_path / "openpyxl.xlsx"), zipfile.ZipFile(tmp_path / "ours.xlsx")
    assert sorted(a.namelist()) == sorted(b.namelist())
    assert "xl/charts/chart1.xml" in a.namelist() and "xl/media/image1.png" in a.namelist()
    for name in a.namelist():
        if name != "docProps/core.xml":  # its modified time
            assert a.read(name) == b.read(name), name
    assert b.read("xl/media/image1.png") == png.read_bytes()
    kinds = {info.filename: info.compress_type for info in b.infolist()}
    assert kinds.pop("xl/media/image1.png") == zipfile.ZIP_STORED
    assert set(kinds.values()) == {zipfile.ZIP_DEFLATED}


def test_without_the_chart_hook_the_save_builds_the_charts_itself(tmp_path, monkeypatch):
    """An openpyxl whose charts lack ``_write`` leaves get_ready with nothing built; the save still writes
    the chart (built by openpyxl at save time) as openpyxl's own save does."""
    from matplotlib.image import imsave
    from openpyxl.chart._chart import ChartBase

    png = tmp_path / "noise.png"
    imsave(png, np.random.default_rng(2).integers(0, 255, (10, 10, 3), dtype=np.uint8))
    _workbook(png).save(tmp_path / "openpyxl.xlsx")
    ours = _workbook(png)
    with monkeypatch.context() as patch:
        patch.setattr(ChartBase, "_write", None)
        saving.get_ready(ours)
    assert "_write" not in vars(ours.worksheets[0]._charts[0])  # nothing pre-built on the chart
    saving.save(ours, tmp_path / "ours.xlsx")
    a, b = zipfile.ZipFile(tmp_path / "openpyxl.xlsx"), zipfile.ZipFile(tmp_path / "ours.xlsx")
    assert a.read("xl/charts/chart1.xml") == b.read("xl/charts/chart1.xml")
