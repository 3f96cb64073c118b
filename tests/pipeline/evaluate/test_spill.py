"""Frames kept on disk for a long span: read back as the frames themselves concatenated would be."""

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.evaluate.spill import SpilledFrames


def _errors(ranges, aircraft, errors) -> pd.DataFrame:
    return pd.DataFrame({"range_nm": np.asarray(ranges, float), "aircraft": pd.Categorical(aircraft),
                         "error_m": np.asarray(errors, float)})


def test_frames_come_back_in_order_with_every_bit_of_their_values(tmp_path):
    """Values no decimal text would keep (the next double after 4, a tiny subnormal, NaN, -0.0), windows
    whose aircraft differ (so the whole is text, as pd.concat makes it) and an empty window between."""
    first = _errors([1.0, 2.5], ["b", "a"], [3.0, np.nextafter(4.0, 5.0)])
    empty = _errors([], [], [])
    second = _errors([np.nan, -0.0], ["c", "a"], [5e-324, 7.25])
    spill = SpilledFrames(tmp_path / "sensor")
    assert not (tmp_path / "sensor").exists(), "no folder before the first frame"
    for frame in (first, empty, second):
        spill.append(frame)
    assert len(spill) == 3
    got = spill.concat()
    assert got["aircraft"].astype(str).tolist() == ["b", "a", "c", "a"]
    assert got["error_m"].to_numpy().view(np.int64).tolist() == np.array(
        [3.0, np.nextafter(4.0, 5.0), 5e-324, 7.25]).view(np.int64).tolist()
    assert np.signbit(got["range_nm"].to_numpy()[3]) and np.isnan(got["range_nm"].to_numpy()[2])
    pd.testing.assert_frame_equal(got, pd.concat([first, empty, second], ignore_index=True))


def test_windows_with_the_same_aircraft_stay_categorical(tmp_path):
    one = _errors([1.0], ["x"], [2.0])
    spill = SpilledFrames(tmp_path / "s")
    spill.append(one)
    spill.append(one)
    got = spill.concat()
    assert isinstance(got["aircraft"].dtype, pd.CategoricalDtype)
    pd.testing.assert_frame_equal(got, pd.concat([one, one], ignore_index=True))


def test_nothing_written_is_refused_by_name(tmp_path):
    with pytest.raises(ValueError, match="sensor-3: no frame was written"):
        SpilledFrames(tmp_path / "sensor-3").concat()


def test_a_folder_that_cannot_be_written_says_what_the_file_was_for(tmp_path):
    (tmp_path / "taken").write_text("a file where the folder should be")
    spill = SpilledFrames(tmp_path / "taken" / "sensor-0")
    with pytest.raises(OSError, match="TMPDIR chooses their folder") as caught:
        spill.append(_errors([1.0], ["x"], [2.0]))
    assert caught.value.filename == str(tmp_path / "taken" / "sensor-0" / "0000000.parquet")
    assert len(spill) == 0
