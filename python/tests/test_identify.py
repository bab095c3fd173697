"""`indentify.identify`: the result's fields, progress callbacks, overrides, report
directories, real data, errors and Ctrl-C."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import indentify
from conftest import R1, REAL_MAXWELL


def test_r1_synthesized_identification(coarse):
    seen = []
    r = indentify.identify(R1, sets=coarse, progress=seen.append)
    assert isinstance(r, indentify.Result)
    assert r.converged is True
    assert r.undetermined == []
    assert isinstance(r.stop_reason, str) and r.stop_reason
    assert r.params["E"] == pytest.approx(20000, rel=1e-4)
    assert r.params["eta"] == pytest.approx(30000, rel=1e-4)
    assert r.params["nu"] == 0.3
    assert r.free == {"E": True, "nu": False, "eta": True}
    assert r.bounds["E"] == (1000.0, 1e6)
    assert r.truth == {"E": 20000.0, "nu": 0.3, "eta": 30000.0}
    # uncertainties: floats for the free parameters, None for the held one
    assert r.std["nu"] is None
    assert isinstance(r.std["E"], float) and r.std["E"] >= 0
    # correlation of the free parameters
    assert r.correlation_names == ["E", "eta"]
    assert r.correlation.dtype == np.float64 and r.correlation.shape == (2, 2)
    np.testing.assert_allclose(np.diag(r.correlation), 1.0)
    np.testing.assert_allclose(r.correlation, r.correlation.T)
    # the fit
    assert set(r.fit) == {"t", "h", "F_data", "F_fit", "F_start"}
    n = len(r.fit["t"])
    assert all(a.shape == (n,) and a.dtype == np.float64 for a in r.fit.values())
    np.testing.assert_allclose(r.fit["F_fit"], r.fit["F_data"], atol=1e-6 * r.fit["F_data"].max())
    assert r.J < r.J_start
    # history and progress: the same dicts
    assert len(r.history) == len(seen) == r.iterations + 1
    assert seen[0]["iteration"] == 0 and seen[-1]["iteration"] == r.iterations
    assert set(seen[0]) == {
        "iteration", "params", "J", "grad_norm", "forward_solves", "adjoint_solves",
        "sensitivity_solves", "seconds",
    }
    assert seen[0]["params"]["E"] == 4000.0
    assert r.history == seen
    assert r.seconds > 0 and r.wall_seconds >= r.seconds
    assert r.parameters[0]["name"] == "E" and r.parameters[0]["unit"] == "MPa"
    assert r.quality["r2"] > 0.999999
    assert r.files is None
    assert "converged=True" in repr(r)


def test_dict_config_and_overrides(coarse):
    cfg = indentify.load_config(R1, sets=coarse)
    r = indentify.identify(cfg, method="lm", max_iterations=2)
    assert r.method == "lm"
    assert r.iterations <= 2
    assert not r.converged
    assert "iteration limit" in r.stop_reason
    r = indentify.identify(cfg, free=["E"], fixed={"eta": 30000.0}, start={"E": 15000.0})
    assert r.free["eta"] is False and r.params["eta"] == 30000.0
    assert r.params["E"] == pytest.approx(20000, rel=1e-4)
    with pytest.raises(indentify.ConfigError, match="unknown method `newton`"):
        indentify.identify(cfg, method="newton")
    with pytest.raises(indentify.ConfigError, match="young"):
        indentify.identify(cfg, free=["young"])


def test_identify_from_in_memory_data(coarse):
    c = indentify.simulate(R1, sets={**coarse, "law.E": 30000})
    r = indentify.identify(R1, data=c, sets=coarse)
    assert r.converged and r.truth is None
    assert r.params["E"] == pytest.approx(30000, rel=1e-4)


def test_closed_form_start(coarse):
    """`start="closed-form"` starts R1's E and eta from Lee and Radok's Maxwell pre-fit of
    the curve (corrected by one forward run), says so in `Result.start`, and ends where the
    configuration's start ends."""
    c = indentify.simulate(R1, sets={**coarse, "law.E": 30000})
    plain = indentify.identify(R1, data=c, sets=coarse)
    r = indentify.identify(R1, data=c, sets=coarse, start="closed-form")
    assert plain.start is None
    assert "Lee and Radok" in r.start["method"], r.start
    values = dict(r.start["values"])
    assert set(values) == {"E", "eta"}, r.start
    assert values["E"] == pytest.approx(30000, rel=0.05)
    assert r.converged and r.iterations <= plain.iterations
    assert r.params["E"] == pytest.approx(plain.params["E"], rel=1e-4)


def test_a_report_directory_is_written_and_protected(coarse, tmp_path):
    out = tmp_path / "report"
    r = indentify.identify(R1, sets=coarse, out=out, max_iterations=3)
    assert (out / "result.json").is_file() and (out / "history.csv").is_file()
    assert r.files["result"] == str(out / "result.json")
    with pytest.raises(indentify.IoError) as e:
        indentify.identify(R1, sets=coarse, out=out, max_iterations=3)
    assert e.value.kind == "io" and "force=True" in str(e.value)
    assert "--force" not in str(e.value) and "--out" not in str(e.value)
    indentify.identify(R1, sets=coarse, out=out, max_iterations=3, force=True)


def test_real_anton_paar_data():
    r = indentify.identify(REAL_MAXWELL)
    assert r.converged
    assert "anonNI.TXT" in r.data
    assert 100 < r.params["E"] < 1e5
    assert r.quality["r2"] > 0.9


def test_a_progress_exception_stops_the_run_and_is_raised(coarse):
    calls = []

    def progress(rec):
        calls.append(rec["iteration"])
        if rec["iteration"] == 2:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        indentify.identify(R1, sets=coarse, progress=progress)
    assert calls == [0, 1, 2]


def test_progress_must_be_callable(coarse):
    with pytest.raises(TypeError, match="progress: expected a callable"):
        indentify.identify(R1, sets=coarse, progress=42)


def test_a_start_that_cannot_be_solved_is_an_error(coarse):
    with pytest.raises(indentify.SolverError) as e:
        indentify.identify(R1, sets={**coarse, "solver.max_iterations": 1, "solver.max_cuts": 0})
    assert e.value.kind == "solver"


def _interrupted_run(delay, full):
    """One identification with SIGINT sent after `delay` s: (raised, seconds, iterations)."""
    timer = threading.Timer(delay, os.kill, (os.getpid(), signal.SIGINT))
    seen = []
    start = time.perf_counter()
    timer.start()
    raised = False
    try:
        indentify.identify(R1, max_iterations=200, progress=seen.append)
    except KeyboardInterrupt:
        raised = True
    finally:
        timer.cancel()
    return raised, time.perf_counter() - start, len(seen)


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(), reason="signals")
def test_ctrl_c_stops_after_the_iteration_and_raises_keyboard_interrupt():
    # the full R1 mesh: long enough to be interrupted (about 60 ms per iteration). A signal
    # is a timing matter on a shared machine: up to three tries, one must show it.
    full = indentify.identify(R1, max_iterations=200)
    # a process started in the background by a non-interactive shell (as CI may be) inherits
    # SIGINT ignored, and Python then installs no KeyboardInterrupt handler: install it
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _tries(full)
    finally:
        signal.signal(signal.SIGINT, previous)


def _tries(full):
    tries = []
    for delay in (0.3, 0.5, 0.8):
        if delay > full.wall_seconds / 3:
            delay = full.wall_seconds / 4
        raised, seconds, iterations = _interrupted_run(delay, full)
        tries.append((delay, raised, seconds, iterations))
        if raised and seconds < full.wall_seconds and 0 < iterations < len(full.history):
            return
    pytest.fail(f"Ctrl-C did not stop the run: (delay, raised, seconds, iterations) = {tries}")


def test_refine_false_skips_the_discretization_check_which_is_returned_when_run(coarse):
    r = indentify.identify(R1, sets=coarse, refine=False)
    assert r.converged and r.discretization is None
    r = indentify.identify(R1, sets=coarse)
    d = r.discretization
    assert set(d) == {
        "mesh", "steps", "rms", "rms_rel", "max_abs", "shift", "relative_shift",
        "exceeds_std", "seconds",
    }
    assert set(d["shift"]) == {"E", "nu", "eta"}
    assert d["shift"]["nu"] is None and isinstance(d["shift"]["E"], float)
    assert d["relative_shift"]["E"] == pytest.approx(d["shift"]["E"] / r.params["E"])
    assert d["rms"] > 0 and 0 < d["rms_rel"] < 1 and d["max_abs"] >= d["rms"]
    # exact data: the deviations are at round-off, so the refinement's shift exceeds them
    assert set(d["exceeds_std"]) <= {"E", "eta"}
    assert isinstance(r.caveats, list) and all(isinstance(c, str) for c in r.caveats)


def test_bad_arguments_are_named_as_python_arguments(coarse):
    with pytest.raises(indentify.ConfigError) as e:
        indentify.identify(R1, sets={**coarse, "law.E": -1}, refine=False)
    msg = str(e.value)
    assert "--set" not in msg and "sets {" in msg and "law.E=-1" in msg, msg
    # one name as a str is a list of one
    r = indentify.identify(R1, sets=coarse, free="E", refine=False, max_iterations=2)
    assert r.free == {"E": True, "nu": False, "eta": False}
    with pytest.raises(TypeError, match=r"free\[1\] = 3: expected a parameter name"):
        indentify.identify(R1, sets=coarse, free=["E", 3])
    with pytest.raises(TypeError, match=r"free: expected a list of parameter names"):
        indentify.identify(R1, sets=coarse, free=3)
    with pytest.raises(TypeError, match=r"fixed\[\"eta\"\] = 'x': expected a number"):
        indentify.identify(R1, sets=coarse, fixed={"eta": "x"})
    # negative integers name their argument and range
    cases = [
        (lambda: indentify.identify(R1, sets=coarse, max_iterations=-1), "max_iterations = -1"),
        (lambda: indentify.identify(R1, sets=coarse, noise=0.01, seed=-3), "seed = -3"),
        (lambda: indentify.simulate(R1, sets=coarse, test=0), "test = 0"),
        (lambda: indentify.gradient(R1, sets=coarse, test=-1), "test = -1"),
        (lambda: indentify.read_record(REAL_MAXWELL, test=-2), "test = -2"),
        (lambda: indentify.make_map("unused", n=-2), "n = -2"),
        (lambda: indentify.design(R1, jobs=-4), "jobs = -4"),
    ]
    for call, needle in cases:
        with pytest.raises(indentify.ConfigError, match="is not allowed: expected an integer"):
            try:
                call()
            except indentify.ConfigError as err:
                assert needle in str(err), str(err)
                raise
