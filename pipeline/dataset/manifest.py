"""The dataset's manifest (``manifest.json``): msdc's version and, per input completely ingested, its
SHA-256, size, format, editions, rows per category and the parts written with their rows, byte ranges, sizes
and CRC-32s.

An input is in the manifest only once every part of it is in place: the manifest is rewritten (to a temporary
file renamed over the old one) after its parts, so a part the manifest does not list belongs to an ingest
that did not finish, and the next ingest removes it (``discard_unlisted``)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from msdc.pipeline.dataset.layout import MANIFEST, PART_GLOB, TEMP_GLOB, relative

FORMAT = "msdc-dataset"
FORMAT_VERSION = 1


class ManifestError(ValueError):
    """The manifest cannot be read as a dataset's: the message names the file and the reason."""


@dataclass
class Manifest:
    """The inputs completely ingested, keyed by SHA-256, in the order they were (each a dict as the ingest
    job makes it: pipeline.jobs.ingest)."""

    inputs: dict[str, dict] = field(default_factory=dict)
    msdc: str = ""

    def parts(self) -> set[str]:
        """Every listed part, relative to the dataset's root."""
        return {p["path"] for rec in self.inputs.values() for p in rec["parts"]}

    def labels(self) -> dict[str, str]:
        """The ``file`` label of each ingested input, to its SHA-256."""
        return {rec["file"]: sha for sha, rec in self.inputs.items()}

    def to_json(self) -> dict:
        """The manifest as written."""
        return {"format": FORMAT, "format_version": FORMAT_VERSION, "msdc": self.msdc,
                "inputs": list(self.inputs.values())}  # in the order they were ingested


def load(root: Path) -> Manifest:
    """The manifest of the dataset at ``root`` (empty when there is none yet); ManifestError if unreadable."""
    path = root / MANIFEST
    if not path.exists():
        return Manifest()
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ManifestError(f"{path}: cannot be read as a dataset manifest: {exc}") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ManifestError(f"{path}: not an msdc dataset manifest (no \"format\": \"{FORMAT}\")")
    if doc.get("format_version") != FORMAT_VERSION:
        raise ManifestError(f"{path}: dataset format version {doc.get('format_version')!r}; this msdc reads "
                            f"version {FORMAT_VERSION}")
    try:
        inputs = {rec["sha256"]: rec for rec in doc["inputs"]}
        for rec in inputs.values():
            [p["path"] for p in rec["parts"]]  # noqa: B018 - every part listed with its path
    except (KeyError, TypeError) as exc:
        raise ManifestError(f"{path}: an input record lacks {exc}") from None
    for rec in inputs.values():
        problem = _record_problem(rec)
        if problem:
            raise ManifestError(f"{path}: the input {rec.get('file', rec['sha256'])!r}: {problem}")
    return Manifest(inputs, str(doc.get("msdc", "")))


def _record_problem(rec: dict) -> str | None:
    """What makes an input record unreadable (its date, or a part's date, category, sensor, rows, path, size
    or CRC-32): the readers would fail on it later, with no file named. None when it reads."""
    from msdc.asterix.categories import DECODABLE
    from msdc.pipeline.dataset.integrity import record_problem

    if rec.get("date") is not None and _no_date(rec["date"]):
        return f"date {rec['date']!r} is no date (YYYY-MM-DD)"
    if not isinstance(rec.get("rows", {}), dict):
        return f"rows {rec['rows']!r} is no table of rows per category"
    for part in rec["parts"]:
        where = f"part {part.get('path')!r}"
        inside = isinstance(part["path"], str) and not Path(part["path"]).is_absolute()
        if not inside or ".." in Path(part["path"]).parts:
            return f"{where}: no path inside the dataset"
        if _no_date(part.get("date")):
            return f"{where}: date {part.get('date')!r} is no date (YYYY-MM-DD)"
        if type(part.get("category")) is not int or part["category"] not in DECODABLE:
            return f"{where}: category {part.get('category')!r} is none msdc decodes"
        if not isinstance(part.get("sensor"), str):
            return f"{where}: sensor {part.get('sensor')!r} is no SAC_SIC text"
        if type(part.get("rows")) is not int or part["rows"] < 0:
            return f"{where}: rows {part.get('rows')!r} is no count"
        checksum = record_problem(part)
        if checksum:
            return f"{where}: {checksum}"
    return None


def _no_date(text) -> bool:
    import datetime as dt

    try:
        dt.date.fromisoformat(text)
    except (TypeError, ValueError):
        return True
    return False


def save(root: Path, manifest: Manifest) -> None:
    """Write the manifest whole: to a temporary file, flushed, then renamed over the old one (a reader or a
    restart sees the old manifest or the new, never a part of one)."""
    path = root / MANIFEST
    tmp = path.with_name(f".{MANIFEST}.tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(manifest.to_json(), fh, indent=1)
        fh.write("\n")
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def discard_unlisted(root: Path, manifest: Manifest) -> list[Path]:
    """Remove what an interrupted ingest left: parts the manifest does not list, temporary parts and a
    temporary manifest, then the partition folders left empty; the files removed."""
    listed = manifest.parts()
    removed = [p for p in root.glob(PART_GLOB) if relative(root, p) not in listed]
    removed += list(root.glob(TEMP_GLOB))
    tmp_manifest = root / f".{MANIFEST}.tmp"
    if tmp_manifest.exists():
        removed.append(tmp_manifest)
    for p in removed:
        p.unlink(missing_ok=True)
    prune_empty(root, {p.parent for p in removed})
    return removed


def prune_empty(root: Path, folders) -> None:
    """Remove the partition folders among ``folders`` (and their parents up to the root) left empty."""
    for folder in sorted(set(folders), key=lambda p: len(p.parts), reverse=True):
        d = folder
        while d != root and root in d.parents:
            try:
                d.rmdir()
            except OSError:  # not empty (or gone): stop climbing
                break
            d = d.parent
