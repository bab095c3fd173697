"""`indentify.read_record`: formats, preprocessing, metadata, numpy arrays and errors."""

import pathlib

import numpy as np
import pytest

import indentify
from conftest import ANTON_PAAR, ANTON_PAAR_MULTI, HYSITRON_HLD


def test_anton_paar_record_has_float64_arrays_and_metadata():
    r = indentify.read_record(str(ANTON_PAAR))
    assert isinstance(r, indentify.Record)
    for a in (r.t, r.h, r.F):
        assert isinstance(a, np.ndarray)
        assert a.dtype == np.float64
        assert a.shape == (len(r),)
    assert r.segment is not None and r.segment.dtype == np.uint32
    assert r.segment.shape == r.t.shape
    assert r.t[0] == 0.0 and np.all(np.diff(r.t) >= 0)
    # 11.13 mN and about 2 um: internal units N and mm
    assert 5e-3 < r.F.max() < 20e-3
    assert 1e-3 < r.h.max() < 3e-3
    meta = r.metadata
    assert isinstance(meta, dict)
    assert meta["format"] == "AntonPaar"
    assert any(q["name"] == "EIT" for q in meta["results"])
    assert [a["step"] for a in r.applied] == ["zero_point", "segments"]
    assert "anonNI" in repr(r)


def test_pathlike_and_format_name_are_accepted():
    a = indentify.read_record(pathlib.Path(ANTON_PAAR), format="anton-paar")
    b = indentify.read_record(str(ANTON_PAAR))
    np.testing.assert_array_equal(a.F, b.F)


def test_preprocessing_dict_false_and_defaults():
    raw = indentify.read_record(ANTON_PAAR, preprocessing=False)
    default = indentify.read_record(ANTON_PAAR)
    resampled = indentify.read_record(ANTON_PAAR, preprocessing={"resample": {"n": 60}})
    assert raw.applied == []
    assert [a["step"] for a in default.applied] == ["zero_point", "segments"]
    assert len(raw) >= len(default)  # the zero point trims the approach, if any
    assert len(resampled) == 60
    assert resampled.applied[-1]["step"] == "resample"


def test_multi_test_file_needs_a_test():
    with pytest.raises(indentify.DataError) as e:
        indentify.read_record(ANTON_PAAR_MULTI)
    assert "none is selected" in str(e.value)
    r = indentify.read_record(ANTON_PAAR_MULTI, test=2)
    assert r.metadata["test_name"]
    assert r.F.max() > 0.05  # 100 mN


def test_hysitron_hld_reads():
    r = indentify.read_record(HYSITRON_HLD)
    assert r.metadata["format"] == "Hld"
    assert r.F.max() > 0.01  # 50 mN


def test_missing_file_is_a_data_error(tmp_path):
    missing = tmp_path / "nope.TXT"
    with pytest.raises(indentify.DataError) as e:
        indentify.read_record(missing)
    assert isinstance(e.value, indentify.Error)
    assert e.value.kind == "data"
    assert str(missing) in e.value.messages[0]
    assert len(e.value.messages) == 2  # what failed, then why
    assert str(e.value) == "\n".join(e.value.messages)


def test_nan_in_a_file_is_a_data_error(tmp_path):
    f = tmp_path / "curve.csv"
    f.write_text("t,h,F\n0,0,0\n1,0.001,nan\n2,0.002,0.002\n")
    with pytest.raises(indentify.DataError) as e:
        indentify.read_record(f, preprocessing=False)
    assert "curve.csv" in str(e.value)


def test_bad_options_are_config_errors():
    with pytest.raises(indentify.ConfigError, match="unknown format `tiff`"):
        indentify.read_record(ANTON_PAAR, format="tiff")
    with pytest.raises(indentify.ConfigError, match="resampel"):
        indentify.read_record(ANTON_PAAR, preprocessing={"resampel": {"n": 60}})
    with pytest.raises(indentify.ConfigError, match="invalid preprocessing"):
        indentify.read_record(ANTON_PAAR, preprocessing={"resample": {"n": "sixty"}})


def test_wrong_types_are_type_errors():
    with pytest.raises(TypeError, match="expected a path"):
        indentify.read_record([str(ANTON_PAAR)])
    with pytest.raises(TypeError):
        indentify.read_record(ANTON_PAAR, test="two")
