"""`indentify.analyze`, `indentify.calibrate` and the start from the Oliver-Pharr analysis:
the dicts have the keys of the CLI's --json, the values are the vendor's own O&P values of
the Anton Paar sphere file, and `identify(start="oliver-pharr")` starts from `first_guess`."""

import json

import pytest

import indentify
from conftest import ANTON_PAAR, ANTON_PAAR_MULTI, EXAMPLES, R1, REAL_MAXWELL

KLA = EXAMPLES / "data" / "kla-fused-silica" / "FusedSilica.xlsx"


def test_analyze_gives_the_vendors_values_in_internal_units(tmp_path):
    r = indentify.analyze(ANTON_PAAR_MULTI, tip="sphere:10", epsilon="m", out=tmp_path)
    assert len(r["tests"]) == 4
    for t in r["tests"]:
        assert t["error"] is None
        for key in ("E", "H", "Er", "S", "hc", "hmax", "Fmax"):
            assert isinstance(t[key], float), key
        vendor = {q["name"]: q["value"] for q in t["vendor"]}
        # E and H in MPa, the vendor's in GPa (within 0.2 %)
        assert t["E"] * 1e-3 == pytest.approx(vendor["EIT (O&P)"], rel=2e-3)
        assert t["H"] * 1e-3 == pytest.approx(vendor["HIT (O&P)"], rel=2e-3)
    assert r["tip"]["modulus"] == pytest.approx(1141e3)
    assert (tmp_path / "analysis.json").is_file()
    assert (tmp_path / "figures" / "unloading-1.svg").is_file()
    # the same keys as the CLI's --json (written as analysis.json)
    written = json.loads((tmp_path / "analysis.json").read_text())
    assert set(written) == set(r)
    assert set(written["tests"][0]) == set(r["tests"][0])


def test_analyze_one_test_and_bad_input():
    r = indentify.analyze(ANTON_PAAR_MULTI, test=2, tip="sphere:10")
    assert [t["index"] for t in r["tests"]] == [2]
    with pytest.raises(indentify.ConfigError, match="not a known shape"):
        indentify.analyze(ANTON_PAAR, tip="pyramid")
    with pytest.raises(indentify.ConfigError, match="epsilon"):
        indentify.analyze(ANTON_PAAR, epsilon="often")


def test_calibrate_writes_a_tip_that_analyze_reads(tmp_path):
    tip = tmp_path / "tip.ron"
    c = indentify.calibrate(KLA, modulus=72e3, nu=0.179, out=tip, tests=[1, 3, 5, 7, 9, 11, 13, 15])
    for key in ("tip", "compliance", "compliance_used", "area", "er", "skipped", "written"):
        assert key in c, key
    assert c["compliance_used"] > 0
    assert tip.is_file()
    # the even tests against the calibration: fused silica's 72 GPa within 3 %
    for k in (2, 4):
        r = indentify.analyze(KLA, test=k, tip=str(tip), nu=0.179)
        assert r["tests"][0]["E"] == pytest.approx(72e3, rel=0.03)


def test_first_guess_and_identify_start_from_the_analysis():
    g = indentify.first_guess(REAL_MAXWELL)
    assert set(g["starts"]) == {"E", "eta"}  # nu is held
    assert g["starts"]["E"] == pytest.approx(g["op"]["E"])
    assert g["op"]["E"] > 0 and g["notes"]
    # the O&P E of the same record as analyze gives it (Berkovich, nu 0.3)
    a = indentify.analyze(ANTON_PAAR)
    assert g["op"]["E"] == pytest.approx(a["tests"][0]["E"], rel=1e-12)
    res = indentify.identify(
        REAL_MAXWELL,
        sets={"data.preprocessing.resample.n": 16, "specimen.elements_in_contact": 4},
        start="oliver-pharr",
        max_iterations=0,
        refine=False,
    )
    starts = {p["name"]: p["start"] for p in res.parameters}
    assert starts["E"] == pytest.approx(g["starts"]["E"])
    assert starts["eta"] == pytest.approx(g["starts"]["eta"])
    with pytest.raises(TypeError, match="oliver-pharr"):
        indentify.identify(REAL_MAXWELL, start=3.0, max_iterations=0)


def test_result_carries_the_oliver_pharr_numbers_beside_the_fit(coarse):
    res = indentify.identify(
        REAL_MAXWELL,
        sets={"data.preprocessing.resample.n": 16, "specimen.elements_in_contact": 4},
        max_iterations=0,
        refine=False,
    )
    op = res.oliver_pharr
    assert isinstance(op, dict)
    assert "skipped" not in op
    # the same test as analyze gives it (the configuration's Berkovich, its nu 0.3)
    a = indentify.analyze(ANTON_PAAR)["tests"][0]
    for key in ("E", "H", "S", "hc", "hmax", "Fmax"):
        assert op[key] == pytest.approx(a[key], rel=1e-12), key
    assert op["E_fe"] == pytest.approx(res.params["E"])
    assert op["E_difference_pct"] == pytest.approx(
        100.0 * (op["E"] - op["E_fe"]) / op["E_fe"], rel=1e-9
    )
    assert "Berkovich" in op["tip"] and op["why_they_differ"]
    assert res.tests == []
    # synthesized data: no record, no analysis
    syn = indentify.identify(R1, sets=coarse, max_iterations=0, refine=False)
    assert syn.oliver_pharr is None
