"""The README's Python example runs as shown: its ```python block is executed from the
repository's root (R1 and the shipped Berkovich record), so an API change that breaks it
fails here."""

import contextlib
import io

from conftest import ROOT


def readme_python_block():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    start = text.index("```python\n") + len("```python\n")
    return text[start : text.index("```", start)]


def test_the_readme_python_example_runs(monkeypatch):
    code = readme_python_block()
    assert "indentify.identify(" in code and "indentify.read_record(" in code
    monkeypatch.chdir(ROOT)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    printed = out.getvalue().splitlines()
    # the line of res.params["E"], res.std["E"], res.converged: R1 from exact data converges
    assert len(printed) > 3 and printed[-2].endswith("True"), printed
