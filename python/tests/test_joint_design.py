"""Joint configurations (`tests: [...]`), the noise model of the deviations
(`noise_model=`, the configuration's `identify.noise`) and `indentify.design`, on small
Maxwell set-ups (8 x 8 mesh, a few steps) so that each call takes well under a second."""

import numpy as np
import pytest

import indentify

# R1's Maxwell law on a coarse mesh, two tests at loading rates a decade apart
MESH = "specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, grading_z: 1.3)"
LAW = "law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0)"
IDENTIFY = """identify: (params: {
        "E": Free(start: 15000.0, lower: 1000.0, upper: 1000000.0),
        "nu": Fixed(value: 0.3),
        "eta": Free(start: 50000.0, lower: 1000.0, upper: 10000000.0),
    }, method: Lm)"""


def history(load_s):
    return (
        f"(segments: [(duration: {load_s}, depth: 0.1, steps: 8), "
        f"(duration: 1.0, depth: 0.1, steps: 6)])"
    )


JOINT = f"""(
    {MESH},
    punch: Cone(half_angle_deg: 68.0),
    {LAW},
    tests: [
        (name: "fast", history: {history(0.1)}),
        (name: "slow", history: {history(1.0)}, weight: 2.0),
    ],
    {IDENTIFY},
)"""

SINGLE = f"""(
    {MESH},
    punch: Cone(half_angle_deg: 68.0),
    {LAW},
    history: {history(1.0)},
    {IDENTIFY},
)"""

DESIGN = f"""(
    {MESH},
    punch: Cone(half_angle_deg: 68.0),
    {LAW},
    history: {history(1.0)},
    {IDENTIFY},
    design: (
        noise: Relative(0.01),
        candidates: [
            (name: "load only", tests: [(history: (segments: [(duration: 1.0, depth: 0.1, steps: 8)]))]),
            (name: "load and hold", tests: [(history: {history(1.0)})]),
            (name: "two rates", tests: [(history: {history(0.1)}), (history: {history(1.0)})]),
        ],
    ),
)"""


def test_joint_identification_reports_every_test():
    r = indentify.identify(JOINT)
    assert r.converged, r.stop_reason
    assert r.params["E"] == pytest.approx(20000, rel=1e-5)
    assert r.params["eta"] == pytest.approx(30000, rel=1e-5)
    assert [t["name"] for t in r.tests] == ["fast", "slow"]
    fast, slow = r.tests
    assert slow["weight"] == 2.0 and slow["default_weight"] is False
    assert fast["default_weight"] is True and fast["weight"] > 0
    # the tests' curves laid end to end are the whole fit
    n = [len(t["fit"]["t"]) for t in r.tests]
    assert sum(n) == len(r.fit["t"])
    np.testing.assert_array_equal(
        np.concatenate([t["fit"]["F_fit"] for t in r.tests]), r.fit["F_fit"]
    )
    for t in r.tests:
        assert set(t["fit"]) == {"t", "h", "F_data", "F_fit", "F_start"}
        assert t["quality"]["r2"] > 0.999999
        assert t["wJ"] >= 0
    # J = sum_k w_k J_k
    assert sum(t["wJ"] for t in r.tests) == pytest.approx(r.J, rel=1e-9, abs=1e-30)


def test_one_test_config_has_no_tests_list():
    r = indentify.identify(SINGLE)
    assert r.tests == []


def test_simulate_and_gradient_pick_a_test_of_a_joint_config():
    fast = indentify.simulate(JOINT, test=1)
    slow = indentify.simulate(JOINT, test=2)
    assert fast["t"][-1] == pytest.approx(1.1) and slow["t"][-1] == pytest.approx(2.0)
    # the faster load meets a stiffer response at the end of the load
    assert fast["F"][8] > slow["F"][8]
    with pytest.raises(indentify.ConfigError, match="test"):
        indentify.simulate(JOINT)
    with pytest.raises(indentify.ConfigError, match="3"):
        indentify.simulate(JOINT, test=3)
    J, grad = indentify.gradient(JOINT, data=slow, test=2)
    assert J == pytest.approx(0.0, abs=1e-20)
    assert set(grad) >= {"E", "eta"}


# the statistical stop (`identify.stop.step_sigma`, a fraction of each parameter's standard
# deviation) off: the fits are followed to the minimum itself, which the noise model of the
# deviations cannot move
SINGLE_TO_THE_MINIMUM = SINGLE.replace("method: Lm)", "method: Lm, stop: (step_sigma: None))")


def test_noise_model_changes_the_deviations_not_the_parameters():
    noisy = dict(noise=0.02, seed=3)
    base = indentify.identify(SINGLE_TO_THE_MINIMUM, **noisy)
    rel = indentify.identify(SINGLE_TO_THE_MINIMUM, noise_model={"Relative": 0.01}, **noisy)
    est = indentify.identify(SINGLE_TO_THE_MINIMUM, noise_model="RelativeEstimated", **noisy)
    absn = indentify.identify(SINGLE_TO_THE_MINIMUM, noise_model={"Absolute": 1e-3}, **noisy)
    for r in (rel, est, absn):
        assert r.params == base.params
    # with the statistical stop on (the default, 0.1), the stated noise sets the deviations
    # the stop measures its steps in: each fit ends within a tenth of its own deviation of
    # the minimum
    for model in (None, {"Relative": 0.01}, "RelativeEstimated", {"Absolute": 1e-3}):
        kw = dict(noisy) if model is None else dict(noisy, noise_model=model)
        stopped = indentify.identify(SINGLE, **kw)
        for k in ("E", "eta"):
            assert abs(stopped.params[k] - base.params[k]) <= 0.1 * stopped.std[k], (model, k)
    # the sandwich covariance scales with the stated level: twice the level, twice sigma
    rel2 = indentify.identify(SINGLE_TO_THE_MINIMUM, noise_model={"Relative": 0.02}, **noisy)
    assert rel2.std["E"] == pytest.approx(2 * rel.std["E"], rel=1e-9)
    assert rel.std["E"] != pytest.approx(base.std["E"], rel=1e-6)
    abs2 = indentify.identify(SINGLE_TO_THE_MINIMUM, noise_model={"Absolute": 2e-3}, **noisy)
    assert abs2.std["eta"] == pytest.approx(2 * absn.std["eta"], rel=1e-9)
    # with `noise` and no stated model, the deviations assume the noise asked for: uniform
    # multiplicative noise of level a has the standard deviation a / sqrt(3) of F
    stated = indentify.identify(SINGLE_TO_THE_MINIMUM, noise_model={"Relative": 0.02 / 3**0.5}, **noisy)
    for k in ("E", "eta"):
        assert stated.std[k] == pytest.approx(base.std[k], rel=1e-12)
    resid = indentify.identify(SINGLE_TO_THE_MINIMUM, noise_model="Residual", **noisy)
    assert resid.params == base.params
    assert resid.std["E"] != pytest.approx(base.std["E"], rel=1e-6)


@pytest.mark.parametrize(
    "bad, match",
    [
        ({"Relative": -0.01}, "finite number > 0"),
        ({"Absolute": float("nan")}, "noise_model.Absolute"),
        ("Gaussian", "noise_model"),
        ({"Relative": "1%"}, "noise_model"),
    ],
)
def test_bad_noise_model_is_refused(bad, match):
    with pytest.raises(indentify.ConfigError, match=match):
        indentify.identify(SINGLE, noise_model=bad)


def test_design_ranks_the_candidates():
    d = indentify.design(DESIGN, jobs=2)
    names = [c["name"] for c in d["candidates"]]
    assert names == ["load only", "load and hold", "two rates"]
    assert d["names"] == ["E", "eta"]
    assert d["nominal"]["E"] == 20000.0
    assert sorted(d["rank_d"]) == [0, 1, 2] and sorted(d["rank_worst"]) == [0, 1, 2]
    for c in d["candidates"]:
        assert set(c["std"]) == {"E", "eta"}
        for n in ("E", "eta"):
            assert c["rel_std"][n] == pytest.approx(c["std"][n] / d["nominal"][n], rel=1e-12)
        assert c["correlation"].shape == (2, 2)
        assert c["worst"][1] == max(c["rel_std"].values())
    # D-optimal order: log det decreasing
    ld = [d["candidates"][k]["log_det"] for k in d["rank_d"]]
    assert ld == sorted(ld, reverse=True)
    # a second test adds information: the two rates beat the one hold they contain
    two, hold = d["candidates"][2], d["candidates"][1]
    assert two["log_det"] > hold["log_det"]
    assert "two rates" in d["table"]
    # the same with one thread, bit for bit
    d1 = indentify.design(DESIGN, jobs=1)
    assert [c["std"] for c in d1["candidates"]] == [c["std"] for c in d["candidates"]]


def test_design_needs_a_design_section():
    with pytest.raises(indentify.ConfigError, match="design"):
        indentify.design(SINGLE)
