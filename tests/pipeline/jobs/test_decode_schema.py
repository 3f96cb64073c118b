"""msdc decode writes every chunk and every input of a category under one schema fixed from the category's
documented columns (issue 27, items 1 and 2): call signs beyond a first chunk's count do not overflow a
dictionary index, and records of two edition families of one category stay under their own headers."""

from __future__ import annotations

import string
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED

import msdc.asterix as asterix
from msdc.asterix.columns import BY_CATEGORY, columns_for
from msdc.asterix.encode import encode_frame, encode_record
from msdc.asterix.tables import available
from msdc.pipeline.cli import main
from msdc.pipeline.jobs.options import CATEGORIES
from msdc.pipeline.report.record_schema import record_schema

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, ADSB = FIX / "radar.ast", FIX / "adsb.ast"
REAL = SHARED / "real"
REAL_RADAR = REAL / "230502-est-080001_BCN_60MN_08_09.ast"
REAL_ADSB_023 = REAL / "adsb_v023_160510-lebl-220001.ast"
SUFFIXES = [".csv", ".parquet"]


def call_signs(n: int) -> list[str]:
    """``n`` distinct call signs of ICAO characters: 'C' and four base-36 digits."""
    digits = string.digits + string.ascii_uppercase
    return ["C" + "".join(digits[(i // 36**k) % 36] for k in (3, 2, 1, 0)) for i in range(n)]


def plots(names: list[str], start_s: float = 28800.0) -> pd.DataFrame:
    """CAT048 plots of radar 25/201, one per call sign given, 1/8 s apart, each with its own address."""
    n = len(names)
    return pd.DataFrame({"sac": 25, "sic": 201, "time_of_day": start_s + 0.125 * np.arange(n),
                         "rho_nm": 20.0, "theta_deg": 90.0, "callsign": names,
                         "address": [f"{0x400000 + i:06X}" for i in range(n)]})


def read_back(path: Path) -> pd.DataFrame:
    """An output file with every text column as plain text (<NA> when absent), CSV or Parquet."""
    if path.suffix == ".csv":
        frame = pd.read_csv(path, dtype={"callsign": "string", "address": "string", "mode3a": "string"},
                            low_memory=False)
    else:
        frame = pd.read_parquet(path)
    return frame.assign(**{c: frame[c].astype("string") for c in frame.columns
                           if isinstance(frame[c].dtype, pd.CategoricalDtype)})


# ---------------------------------------------------------------------------------------------------------
# item 1: a text column's distinct values in a later chunk or input


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_three_hundred_call_signs_in_a_second_input_after_three_in_the_first(tmp_path, capsys, suffix):
    """The first input's 3 call signs gave an int8 dictionary index that the second input's 300 overflowed
    (ArrowInvalid: Integer value 188 not in range: -128 to 127)."""
    first, second = call_signs(3), call_signs(303)[3:]
    a, b = tmp_path / "a.ast", tmp_path / "b.ast"
    a.write_bytes(encode_frame(48, plots(first)))
    b.write_bytes(encode_frame(48, plots(second, 30000.0)))
    out = tmp_path / f"o{suffix}"
    assert main(["decode", str(a), str(b), "-o", str(out)]) == 0
    assert "Traceback" not in capsys.readouterr().err
    got = read_back(out)
    assert got["callsign"].tolist() == first + second
    assert got["address"].tolist() == [f"{0x400000 + i:06X}" for i in range(3)] + [
        f"{0x400000 + i:06X}" for i in range(300)]
    assert got["file"].tolist() == ["a.ast"] * 3 + ["b.ast"] * 300


def test_a_quiet_first_chunk_then_many_call_signs_in_one_recording(tmp_path):
    """6,000 plots of one aircraft (more than the first 0.1 MB chunk holds), then 400 aircraft: one
    Parquet file with every call sign, and the dictionary index 32-bit in the file's schema."""
    import pyarrow.parquet as pq

    names = ["QUIET1"] * 6000 + call_signs(400)
    path = tmp_path / "day.ast"
    path.write_bytes(encode_frame(48, plots(names)))
    assert len(path.read_bytes()) > 120_000  # more than one 0.1 MB chunk
    out = tmp_path / "day.parquet"
    assert main(["decode", str(path), "--chunk-mb", "0.1", "-o", str(out)]) == 0
    assert read_back(out)["callsign"].tolist() == names
    field = pq.read_schema(out).field("callsign")
    assert str(field.type) == "dictionary<values=string, indices=int32, ordered=0>"


def test_chunks_are_gathered_into_row_groups_of_about_row_group_bytes(tmp_path, monkeypatch):
    """Issue 27 item 6: a row group per chunk grew the writer's metadata with the file. 26,000 plots in
    0.1 MB chunks: one row group while under ROW_GROUP_BYTES, more once it is lowered, rows in order."""
    import pyarrow.parquet as pq

    import msdc.pipeline.jobs.decode as decode

    names = call_signs(26_000)
    path = tmp_path / "day.ast"
    path.write_bytes(encode_frame(48, plots(names)))
    chunks = len(path.read_bytes()) / 100_000
    assert chunks > 5
    out = tmp_path / "day.parquet"
    assert main(["decode", str(path), "--chunk-mb", "0.1", "-o", str(out)]) == 0
    assert pq.ParquetFile(out).metadata.num_row_groups == 1
    assert read_back(out)["callsign"].tolist() == names
    monkeypatch.setattr(decode, "ROW_GROUP_BYTES", 1)  # every chunk written as it comes
    out2 = tmp_path / "day2.parquet"
    assert main(["decode", str(path), "--chunk-mb", "0.1", "-o", str(out2)]) == 0
    assert pq.ParquetFile(out2).metadata.num_row_groups >= int(chunks)
    assert read_back(out2)["callsign"].tolist() == names


@pytest.mark.skipif(not REAL_RADAR.is_file(), reason=f"{REAL_RADAR} not present: the real-recording case is "
                    "skipped")
def test_the_fixture_radar_then_the_real_radar_recording_to_parquet(tmp_path):
    """The issue's command line: the fixture's 5 call signs, then the real hour's hundreds. Every real
    record's call sign and address as the two independent decoders give them (shared/real)."""
    out = tmp_path / "o.parquet"
    assert main(["decode", str(RADAR), str(REAL_RADAR), "-o", str(out)]) == 0
    got = read_back(out)
    real = got[got["file"] == REAL_RADAR.name]
    expected = pd.read_csv(f"{REAL_RADAR}.expected.csv.gz", dtype={"callsign": "string", "address": "string"})
    both = real.merge(expected, on="offset", suffixes=("", "_expected"), validate="1:1")
    assert len(both) == len(expected) == 44_085
    for column in ("callsign", "address"):  # empty in the expected file: a call sign outside the ICAO set
        known = both[f"{column}_expected"].notna()
        assert (both.loc[known, column] == both.loc[known, f"{column}_expected"]).all()
    assert real["callsign"].nunique() > 127


# ---------------------------------------------------------------------------------------------------------
# item 2: every pair of edition families of a category in one output


def families() -> list[tuple[int, str]]:
    """One edition (the newest) of each edition family (a distinct column list) of every category decode
    writes."""
    out: dict[tuple[int, tuple[str, ...]], str] = {}
    for cat in sorted(set(BY_CATEGORY) & set(CATEGORIES)):
        for ed in sorted(available()[cat], key=lambda e: tuple(int(p) for p in e.split("."))):
            out[(cat, tuple(c.name for c in columns_for(cat, ed)))] = ed
    return [(cat, ed) for (cat, _), ed in out.items()]


FAMILY_PAIRS = [(cat, a, b) for cat, a in families() for c2, b in families() if c2 == cat and a != b]


def family_records(cat: int, edition: str, n: int = 4) -> bytes:
    """``n`` records of ``cat`` in ``edition`` giving as many of its columns as encode together, each
    column its own value where the field takes it (so that a value under another column's header shows)."""
    chosen: dict[str, object] = {"sac": 7, "sic": 9}
    for i, col in enumerate(columns_for(cat, edition)):
        tries = {"float": [i + 0.5, 1.0], "int": [i % 5 + 1, 1], "flag": [i % 2, 1], "count": [1],
                 "hex": [f"{0x100000 + i:06X}"], "octal": [f"{i + 1:04o}"], "icao": [f"AB{i}"]
                 }.get(col.kind, [])
        for value in [] if col.name in chosen else tries:
            try:
                encode_record(cat, {**chosen, col.name: value}, edition=edition)
            except ValueError:
                continue
            chosen[col.name] = value
            break
    frame = pd.DataFrame([chosen] * n)
    if "time_of_day" in frame:
        frame["time_of_day"] = 3600.0 + np.arange(n)
    return encode_frame(cat, frame, edition=edition)


def test_every_category_with_several_edition_families_has_its_pairs_tested():
    """CAT021 has two families (2.x, 0.2x): its two orders are among the pairs below."""
    assert {(21, "2.7", "0.26"), (21, "0.26", "2.7")} <= set(FAMILY_PAIRS)


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize("cat, first, second", FAMILY_PAIRS)
def test_two_edition_families_in_one_output_keep_each_value_under_its_own_column(tmp_path, suffix, cat, first,
                                                                                 second):
    """Each input's rows, read back by column name, equal what the reader decodes from that input alone;
    a column the input's edition lacks is empty on its rows; the header is the category's one schema."""
    paths = []
    for ed in (first, second):
        paths.append(tmp_path / f"cat{cat:03d}_{ed}.ast")
        paths[-1].write_bytes(family_records(cat, ed))
    out = tmp_path / f"o{suffix}"
    assert main(["decode", *map(str, paths), "--edition", f"{cat}=auto", "--category", str(cat), "-o",
                 str(out)]) == 0
    got = read_back(out)
    assert list(got.columns) == record_schema(cat).columns
    for path, ed in zip(paths, (first, second), strict=True):
        alone = asterix.read(path, editions={cat: ed}).frames[cat]
        rows = got[got["file"] == path.name].reset_index(drop=True)
        assert len(rows) == len(alone) == 4
        for column in got.columns:
            if column in ("file",):
                continue
            if column not in alone:
                assert rows[column].isna().all(), (ed, column)
                continue
            want = alone[column]
            if isinstance(want.dtype, pd.CategoricalDtype):
                want = want.astype("string")
            if want.dtype.kind == "M" or isinstance(want.dtype, pd.DatetimeTZDtype):
                got_times = pd.to_datetime(rows[column], utc=True)
                assert (got_times.isna() == want.isna()).all() and (got_times[want.notna()] == want[
                    want.notna()]).all(), (ed, column)
                continue
            if pd.api.types.is_numeric_dtype(want.dtype):  # CSV reads a column with empty cells as float
                same = np.array_equal(rows[column].astype("float64").to_numpy(np.float64, na_value=np.nan),
                                      want.astype("float64").to_numpy(np.float64, na_value=np.nan),
                                      equal_nan=True)
            else:
                same = rows[column].astype("string").fillna("<NA>").tolist() == want.astype(
                    "string").fillna("<NA>").tolist()
            assert same, (ed, column, rows[column].tolist(), want.tolist())


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.skipif(not REAL_ADSB_023.is_file(), reason=f"{REAL_ADSB_023} not present: the real-recording "
                    "case is skipped")
def test_the_fixture_adsb_then_the_real_023_recording(tmp_path, suffix):
    """The issue's command line: the fixture (2.7) then the real 0.23 hour, editions chosen per file. The
    0.23 rows' latitudes, longitudes and addresses under their own headers as the two independent decoders
    give them; the 2.x-only columns empty on them, the 0.2x-only ones empty on the fixture's."""
    out = tmp_path / f"o{suffix}"
    assert main(["decode", str(ADSB), str(REAL_ADSB_023), "--edition", "21=auto", "-o", str(out)]) == 0
    got = read_back(out)
    assert list(got.columns) == record_schema(21).columns
    real = got[got["file"] == REAL_ADSB_023.name]
    expected = pd.read_csv(f"{REAL_ADSB_023}.expected.csv.gz", dtype={"address": "string"})
    both = real.merge(expected, on="offset", suffixes=("", "_expected"), validate="1:1")
    assert len(both) == len(expected) == 49_330
    assert (both["latitude"] == both["latitude_expected"]).all()
    assert (both["longitude"] == both["longitude_expected"]).all()
    assert (both["address"] == both["address_expected"]).all()
    fixture = got[got["file"] == ADSB.name]
    assert len(fixture) == len(asterix.read(ADSB).frames[21])
    assert real[["nacp", "rc", "time_applicability_position"]].isna().all().all()
    assert real["fom_pa"].notna().all() and fixture[["fom_pa", "spi"]].isna().all().all()
