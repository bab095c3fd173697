"""`indentify.gradient`: J and dJ/dc against every form of in-memory or file data, and the
data errors (shapes, NaN, lengths, missing files)."""

import numpy as np
import pytest

import indentify
from conftest import R1


@pytest.fixture
def curve(coarse):
    """The coarse R1 curve at the configuration's law values (E = 20000, eta = 30000)."""
    return indentify.simulate(R1, sets=coarse)


def test_at_the_truth_the_misfit_and_gradient_vanish(coarse, curve):
    g = indentify.gradient(R1, data={"t": curve["t"], "F": curve["F"]}, sets=coarse)
    assert isinstance(g, indentify.GradientResult)
    assert g.J < 1e-20
    assert g.names == ["E", "nu", "eta"]
    assert set(g.gradient) == {"E", "nu", "eta"}
    assert all(abs(v) < 1e-12 for v in g.gradient.values())


def test_away_from_the_truth_the_gradient_points_back(coarse, curve):
    J, grad = indentify.gradient(R1, data=curve, sets={**coarse, "law.E": 25000})
    assert J > 0
    assert grad["E"] > 0  # too stiff: decreasing E lowers J
    g = indentify.gradient(R1, data=curve, sets={**coarse, "law.E": 25000})
    assert g.params["E"] == 25000
    assert g.units["E"] == "MPa"
    assert g.forward_seconds > 0 and g.adjoint_seconds > 0
    assert "GradientResult(J=" in repr(g)


def test_every_data_form_gives_the_same_misfit(coarse, curve, tmp_path):
    sets = {**coarse, "law.E": 25000}
    t, h, F = curve["t"], curve["h"], curve["F"]
    ref = indentify.gradient(R1, data={"t": t, "F": F}, sets=sets).J
    f = tmp_path / "curve.csv"
    np.savetxt(f, np.column_stack([t, F]), delimiter=",", header="t,F", comments="")
    forms = [
        {"t": t, "h": h, "F": F},
        {"t": list(t), "F": list(F)},  # lists
        np.column_stack([t, F]),  # (n, 2)
        np.column_stack([t, h, F]),  # (n, 3)
        np.asfortranarray(np.column_stack([t, F])),  # another memory layout
        np.column_stack([t, F]).tolist(),  # a list of rows
        str(f),
        f,
    ]
    for data in forms:
        assert indentify.gradient(R1, data=data, sets=sets).J == pytest.approx(ref, rel=1e-12)
    # integer and float32 dtypes are converted to float64
    Fi = np.round(F * 1e6).astype(np.int64)
    assert indentify.gradient(R1, data={"t": t, "F": Fi / 1e6}, sets=sets).J == pytest.approx(
        indentify.gradient(R1, data={"t": t, "F": Fi.astype(np.float64) / 1e6}, sets=sets).J
    )
    g32 = indentify.gradient(R1, data={"t": t.astype(np.float32), "F": F.astype(np.float32)}, sets=sets)
    assert g32.J == pytest.approx(ref, rel=1e-3)


def test_wrong_shapes_and_values_are_data_errors(coarse, curve):
    t, F = curve["t"], curve["F"]
    bad = {
        "got shape (31, 4)": np.zeros((len(t), 4)),
        "got shape (2, 3, 4)": np.zeros((2, 3, 4)),
        "1-D": {"t": np.zeros((len(t), 2)), "F": F},
        "different lengths": {"t": t, "F": F[:-1]},
        "no `F` column": {"t": t, "f": F},
        "is not allowed: expected finite": {"t": t, "F": np.where(np.arange(len(F)) == 3, np.nan, F)},
        "at least 2": {"t": t[:1], "F": F[:1]},
        "cannot be read as an array": {"t": t, "F": ["a"] * len(t)},
    }
    for what, data in bad.items():
        with pytest.raises(indentify.DataError) as e:
            indentify.gradient(R1, data=data, sets=coarse)
        assert what in str(e.value), (what, str(e.value))
        assert e.value.kind == "data"


def test_no_data_and_missing_data_are_data_errors(coarse, tmp_path):
    with pytest.raises(indentify.DataError, match="no data"):
        indentify.gradient(R1, sets=coarse)
    with pytest.raises(indentify.DataError, match="missing.csv"):
        indentify.gradient(R1, data=tmp_path / "missing.csv", sets=coarse)


def test_data_of_the_wrong_type_is_a_type_error(coarse):
    with pytest.raises(TypeError, match="data: expected"):
        indentify.gradient(R1, data=5, sets=coarse)
