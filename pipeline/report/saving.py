"""Saving msdc's write-only workbooks: openpyxl's writer, with what can be done before the workbook is
complete done beforehand (while another process still draws the figure it waits for) and images stored as
they are (a PNG is compressed already: deflating it again cost time for 4 % of its bytes)."""

from __future__ import annotations

import datetime as dt
import os
from zipfile import ZIP_DEFLATED, ZIP_STORED, ZipFile

from openpyxl import Workbook

from msdc.pipeline.report.files import named

_COMPRESSED_MEDIA = (".png", ".jpeg", ".jpg", ".gif")


class _Archive(ZipFile):
    """The workbook's zip: every part deflated as openpyxl does, but images stored."""

    def writestr(self, zinfo_or_arcname, data, compress_type=None, compresslevel=None):
        name = getattr(zinfo_or_arcname, "filename", zinfo_or_arcname)
        if name.startswith("xl/media/") and name.lower().endswith(_COMPRESSED_MEDIA):
            compress_type = ZIP_STORED
        super().writestr(zinfo_or_arcname, data, compress_type, compresslevel)


def get_ready(wb: Workbook) -> None:
    """What saving ``wb`` needs that its last rows and images do not change, done now: each chart's XML
    tree built (openpyxl builds it from a hundred validated objects; the save then only serialises it) and
    Pillow's image plugins loaded (an image's first opening)."""
    from openpyxl.drawing import image

    if image.PILImage:  # Pillow as openpyxl imported it (matplotlib's dependency too)
        image.PILImage.preinit()
    for ws in wb.worksheets:
        for chart in getattr(ws, "_charts", ()):
            build = getattr(chart, "_write", None)
            if not callable(build):  # an openpyxl without this hook: its save builds the charts as usual
                return
            tree = build()
            chart._write = lambda tree=tree: tree  # what the save calls, answered from the tree built now


def save(wb: Workbook, path: str | os.PathLike[str]) -> None:
    """Save ``wb`` to ``path`` as Workbook.save does (the same parts and content), images stored; an error
    names ``path``."""
    with named(path):
        try:
            from openpyxl.writer.excel import ExcelWriter
        except ImportError:  # an openpyxl that moved its writer: its own save, the PNG deflated again
            wb.save(path)
            return
        archive = _Archive(path, "w", ZIP_DEFLATED, allowZip64=True)
        wb.properties.modified = dt.datetime.now(tz=dt.UTC).replace(tzinfo=None)
        ExcelWriter(wb, archive).save()
