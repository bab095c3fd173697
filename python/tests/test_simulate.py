"""`indentify.simulate` and `load_config`: every form of `config` and `sets`, numpy output,
configuration errors and a solver failure."""

import math
import pathlib

import numpy as np
import pytest

import indentify
from conftest import COARSE, R1


def test_r1_curve_is_float64_arrays(coarse):
    c = indentify.simulate(R1, sets=coarse)
    assert set(c) == {"t", "h", "F", "a"}
    n = len(c["t"])
    assert n == 31  # the start and 3 x 10 steps
    for a in c.values():
        assert isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == (n,)
    assert c["F"][0] == 0.0 and c["F"].max() > 0
    assert math.isclose(c["h"].max(), 0.1)
    assert np.all(np.diff(c["t"]) > 0)


def test_every_config_form_gives_the_same_curve(coarse):
    ref = indentify.simulate(str(R1), sets=coarse)["F"]
    text = R1.read_text()
    as_dict = indentify.load_config(R1)
    for config in (pathlib.Path(R1), text, as_dict, None):
        np.testing.assert_array_equal(indentify.simulate(config, sets=coarse)["F"], ref)
    # the dict with the overrides applied in it
    d = indentify.load_config(R1, sets=coarse)
    assert d["specimen"]["Cylinder"]["nr"] == 8
    np.testing.assert_array_equal(indentify.simulate(d)["F"], ref)


def test_sets_as_dict_list_and_numpy_scalars(coarse):
    base = indentify.simulate(R1, sets=coarse)["F"]
    stiff = indentify.simulate(R1, sets={**coarse, "law.E": 40000})["F"]
    assert stiff.max() > base.max()
    listed = indentify.simulate(R1, sets=[f"{k}={v}" for k, v in coarse.items()] + ["law.E=40000"])
    np.testing.assert_array_equal(listed["F"], stiff)
    numpy_scalars = {**{k: np.int64(v) for k, v in coarse.items()}, "law.E": np.float64(40000.0)}
    np.testing.assert_array_equal(indentify.simulate(R1, sets=numpy_scalars)["F"], stiff)


def test_noise_perturbs_the_force(coarse):
    exact = indentify.simulate(R1, sets=coarse)["F"]
    noisy = indentify.simulate(R1, sets=coarse, noise=0.05, seed=3)["F"]
    assert not np.array_equal(exact, noisy)
    assert np.all(np.abs(noisy - exact) <= 0.05 * np.abs(exact) + 1e-15)
    with pytest.raises(indentify.ConfigError, match="noise"):
        indentify.simulate(R1, sets=coarse, noise=1.5)


def test_a_bad_key_in_a_dict_config_is_named(coarse):
    cfg = indentify.load_config(R1)
    cfg["solver"]["residual_tolerance"] = 1e-9
    with pytest.raises(indentify.ConfigError) as e:
        indentify.simulate(cfg, sets=coarse)
    assert "residual_tolerance" in str(e.value)
    assert e.value.messages[1].startswith("`solver.residual_tolerance`: unknown field `residual_tolerance`, expected one of `residual_tol`")
    assert e.value.kind == "config"
    assert e.value.messages[0] == "cannot read the configuration `<dict>`"


def test_a_string_for_a_number_is_a_config_error(coarse):
    cfg = indentify.load_config(R1)
    cfg["law"]["Maxwell"]["E"] = "stiff"
    with pytest.raises(indentify.ConfigError, match="<dict>") as e:
        indentify.simulate(cfg)
    m = e.value.messages[1]
    assert m.startswith("`law.Maxwell.E`:") and "expected a number" in m and "stiff" in m, e.value.messages
    with pytest.raises(indentify.ConfigError, match="law.E"):
        indentify.simulate(R1, sets={"law.E": "stiff"})
    with pytest.raises(indentify.ConfigError, match="specimen.nr"):
        indentify.simulate(R1, sets={"specimen.nr": 8.5})
    with pytest.raises(indentify.ConfigError, match="unknown key `young`"):
        indentify.simulate(R1, sets={"law.young": 1.0})


def test_out_of_range_and_nan_values_are_config_errors():
    cfg = indentify.load_config(R1)
    cfg["law"]["Maxwell"]["nu"] = 0.7
    with pytest.raises(indentify.ConfigError, match="nu"):
        indentify.simulate(cfg)
    cfg["law"]["Maxwell"]["nu"] = float("nan")
    with pytest.raises(indentify.ConfigError, match="finite"):
        indentify.simulate(cfg)


def test_ron_text_errors_give_the_line():
    with pytest.raises(indentify.ConfigError) as e:
        indentify.simulate("(specimen: Cylinder(radius: 1.0,")
    assert "<RON string>" in str(e.value)


def test_a_missing_config_file_is_a_config_error(tmp_path):
    with pytest.raises(indentify.ConfigError, match="nope.ron"):
        indentify.simulate(tmp_path / "nope.ron")


def test_wrong_argument_types_are_type_errors():
    with pytest.raises(TypeError, match="config: expected a path"):
        indentify.simulate([str(R1)])
    with pytest.raises(TypeError, match="config: expected a path"):
        indentify.simulate(42)
    with pytest.raises(TypeError, match="sets"):
        indentify.simulate(R1, sets=42)
    with pytest.raises(TypeError, match="sets"):
        indentify.simulate(R1, sets="law.E=1")
    with pytest.raises(TypeError, match="keys are dotted paths"):
        indentify.simulate(R1, sets={1: 2})
    with pytest.raises(TypeError, match="cannot use a set"):
        cfg = indentify.load_config(R1)
        cfg["law"]["Maxwell"]["E"] = {1.0}
        indentify.simulate(cfg)


def test_a_failing_step_is_a_solver_error_with_the_partial_curve():
    # one Newton iteration and no step cuts: the contact step cannot converge
    sets = {**COARSE, "solver.max_iterations": 1, "solver.max_cuts": 0}
    with pytest.raises(indentify.SolverError) as e:
        indentify.simulate(R1, sets=sets)
    assert e.value.kind == "solver"
    assert "failed after 0 step cuts" in str(e.value)
    partial = e.value.partial
    assert set(partial) == {"t", "h", "F", "a"}
    assert len(partial["t"]) < 31


def test_a_path_with_parentheses_is_a_path(coarse, tmp_path):
    folder = tmp_path / "run (1)"
    folder.mkdir()
    copy = folder / "r1.ron"
    copy.write_text(R1.read_text())
    np.testing.assert_array_equal(
        indentify.simulate(str(copy), sets=coarse)["F"], indentify.simulate(R1, sets=coarse)["F"]
    )
