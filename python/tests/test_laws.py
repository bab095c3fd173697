"""`indentify.laws()`: the registry's listing (the data of `indentify laws --json`), every
listed parameter accepted by `sets`, and simulate/identify with the laws that have
internal variables (Plastic, Prony) from configuration text and `sets`."""

import json
import os
import shutil
import subprocess

import numpy as np
import pytest

import indentify
from conftest import R1

PLASTIC = "Plastic(E: 20000.0, nu: 0.3, sY: 200.0, hardening: Power(n: 0.2), rate: Norton(K: 300.0, m: 3.0))"
PRONY = "Prony(E: 20000.0, nu: 0.3, terms: [(g: 0.3, tau: 0.1), (g: 0.2, tau: 1.0)])"


def with_law(law):
    """R1's configuration text with `law` in place of its Maxwell law and no `identify`
    section (its parameters are Maxwell's)."""
    text = R1.read_text()
    start = text.index("    law: Maxwell(")
    end = text.index("\n    ),\n", start) + len("\n    ),\n")
    text = text[:start] + "    law: " + law + ",\n" + text[end:]
    return text[: text.index("    identify: (")] + ")\n"


def test_laws_lists_every_registered_law_with_units_and_ranges():
    laws = indentify.laws()
    assert [l["variant"] for l in laws] == ["Elastic", "Maxwell", "NortonHoff", "Plastic", "Prony"]
    plastic = laws[3]
    by_name = {p["name"]: p for p in plastic["parameters"]}
    assert list(by_name) == ["E", "nu", "sY", "H", "K", "m", "n", "Q", "b", "eps0"]
    assert by_name["n"]["set"] == "law.n" and by_name["n"]["range"] == "[0, 1]"
    assert by_name["Q"]["only_in"] == ["hardening: Voce"]
    assert [k["field"] for k in plastic["kinds"]] == ["hardening", "rate"]
    prony = laws[4]
    assert [p["name"] for p in prony["parameters"]] == ["E", "nu", "g1", "tau1", "g2", "tau2"]
    assert prony["lists"] == [{"field": "terms", "fields": ["g", "tau"]}]


def test_the_listing_equals_the_cli_listing():
    exe = os.environ.get("INDENTIFY_EXE") or shutil.which("indentify")
    if not exe:
        if os.environ.get("CI") == "true":
            pytest.fail("no indentify executable under CI (python/run-tests.sh sets INDENTIFY_EXE)")
        pytest.skip("no indentify executable (set INDENTIFY_EXE)")
    out = subprocess.run([exe, "laws", "--json"], check=True, capture_output=True, text=True)
    assert json.loads(out.stdout) == indentify.laws()


@pytest.mark.parametrize("law", [PLASTIC, PRONY])
def test_every_listed_parameter_is_accepted_by_sets(law):
    text = with_law(law)
    variant = law.split("(")[0]
    entry = next(l for l in indentify.laws() if l["variant"] == variant)
    form = next(f for f in entry["forms"] if variant == "Prony" or f["label"] == "hardening: Power, rate: Norton")
    for name in form["parameters"]:
        p = next(q for q in entry["parameters"] if q["name"] == name)
        cfg = indentify.load_config(text)
        value = 0.25 if name in ("n", "g1", "g2", "nu") else 123.0
        got = indentify.load_config(text, sets={p["set"]: value})
        assert got != cfg, name
    with pytest.raises(indentify.ConfigError, match="law.n"):
        indentify.load_config(with_law(PLASTIC), sets={"law.n": 1.5})


def test_simulate_and_identify_take_the_new_laws(coarse):
    for law, key, value in ((PLASTIC, "law.n", 0.3), (PRONY, "law.g2", 0.1)):
        text = with_law(law)
        a = indentify.simulate(text, sets=coarse)
        b = indentify.simulate(text, sets={**coarse, key: value})
        assert a["F"].max() > 0 and not np.array_equal(a["F"], b["F"])
    # Prony's E and g1 from its own curve
    r = indentify.identify(with_law(PRONY), sets=coarse, free=["E", "g1"], start={"E": 15000.0, "g1": 0.2},
                           max_iterations=60)
    assert r.converged
    assert r.params["E"] == pytest.approx(20000.0, rel=1e-4) and r.params["g1"] == pytest.approx(0.3, rel=1e-4)
