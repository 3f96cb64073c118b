"""``read`` plans a recording assuming its decoded blocks walk (no walk per block before decoding), and
settles the plan again when decoding meets one that does not: its records, errors and byte account are
always those of ``iter_read``, which settles the plan walking every block first."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from reader_fuzz import check_chunks, clean_blocks

import msdc.asterix as asterix
from msdc.asterix.containers import read_segments
from msdc.asterix.plan import plan_recording

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"


def _read(path: Path, **kw) -> asterix.Recording:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return asterix.read(path, **kw)


def test_a_clean_recording_is_planned_without_walking_and_reads_as_iter_read():
    data = np.frombuffer((FIXTURES / "radar.ast").read_bytes(), np.uint8)
    seg = read_segments(data, None)
    assert plan_recording(data, seg, {}, None, assume_walking=True).assumed
    assert not plan_recording(data, seg, {}, None).assumed
    whole = _read(FIXTURES / "radar.ast")
    assert whole.errors.empty and whole.frames[48].shape[0] > 0
    assert check_chunks(FIXTURES / "radar.ast", whole, 20_000) == []


def test_a_block_that_does_not_walk_is_decoded_by_the_plan_settled_again(tmp_path, monkeypatch):
    data = bytearray((FIXTURES / "radar.ast").read_bytes())
    starts, lens = clean_blocks(bytes(data))
    k = len(starts) // 2
    at = int(starts[k])
    # every byte of the block's first FSPEC cleared: an empty FSPEC (the spec's FX chain ends at once)
    data[at + 3] = 0
    bad = tmp_path / "bad.ast"
    bad.write_bytes(bytes(data))
    clean = _read(FIXTURES / "radar.ast")
    lost = int((clean.frames[48]["offset"].between(at, at + int(lens[k]) - 1)).sum())
    assert lost >= 1
    import msdc.asterix.plan as plan_module
    planned: list[bool] = []

    def spy(*args, assume_walking: bool = False, **kw):
        planned.append(assume_walking)
        return plan_recording(*args, assume_walking=assume_walking, **kw)

    monkeypatch.setattr(plan_module, "plan_recording", spy)
    whole = _read(bad)
    assert planned == [True, False]  # assumed, then settled again walking every block
    monkeypatch.undo()
    assert len(whole.frames[48]) == len(clean.frames[48]) - lost
    assert at in set(whole.errors["offset"]) or (whole.errors["offset"].between(at, at + int(lens[k]))).any()
    assert check_chunks(bad, whole, 20_000) == []
    assert check_chunks(bad, whole, 3_000) == []


@pytest.mark.parametrize("edition", ["0.23", "0.26"])
def test_a_wrong_pinned_edition_is_judged_as_iter_read_judges_it(edition):
    """Most blocks fail under a wrong edition: the plan settled again withholds or reports them alike."""
    whole = _read(FIXTURES / "adsb.ast", editions={21: edition})
    assert len(whole.errors) > 0
    assert check_chunks(FIXTURES / "adsb.ast", whole, 50_000, editions={21: edition}) == []
