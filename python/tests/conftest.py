"""Shared fixtures of the indentify pytest suite: the repository's paths and small, fast
configurations (R1 Maxwell on a coarse 8 x 8 mesh with 10 steps per segment)."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
R1 = EXAMPLES / "r1-maxwell.ron"
ANTON_PAAR = EXAMPLES / "data" / "anton-paar-unht-berkovich" / "anonNI.TXT"
ANTON_PAAR_MULTI = EXAMPLES / "data" / "anton-paar-sphere-creep" / "HT_V_100mN.TXT"
HYSITRON_HLD = EXAMPLES / "data" / "hysitron" / "Exp-50mN_0000.hld"
REAL_MAXWELL = EXAMPLES / "real" / "anon-maxwell.ron"

# R1 made small: an 8 x 8 mesh, 10 steps per segment (a simulation takes milliseconds)
COARSE = {
    "specimen.nr": 8,
    "specimen.nz": 8,
    "history.segments.0.steps": 10,
    "history.segments.1.steps": 10,
    "history.segments.2.steps": 10,
}


@pytest.fixture
def coarse():
    """A fresh copy of the coarse overrides."""
    return dict(COARSE)
