"""The package itself: exception hierarchy, docstrings, the type stub and make_map."""

import ast
import os
import pathlib

import pytest

import indentify

PUBLIC = [
    "read_record", "simulate", "gradient", "identify", "make_map", "load_config", "laws",
    "Record", "GradientResult", "Result",
    "Error", "ConfigError", "DataError", "SolverError", "IoError",
]


def test_exception_hierarchy():
    assert issubclass(indentify.Error, Exception)
    for cls in (indentify.ConfigError, indentify.DataError, indentify.SolverError, indentify.IoError):
        assert issubclass(cls, indentify.Error)
        assert cls.__module__ == "indentify"


def test_everything_has_a_docstring():
    assert indentify.__doc__
    for name in PUBLIC:
        assert getattr(indentify, name).__doc__, name
    for prop in ("t", "h", "F", "segment", "metadata", "applied"):
        assert getattr(indentify.Record, prop).__doc__, prop
    for prop in ("params", "std", "correlation", "converged", "fit", "history"):
        assert getattr(indentify.Result, prop).__doc__, prop


def test_the_stub_and_py_typed_are_installed_and_complete():
    pkg = pathlib.Path(indentify.__file__).parent
    stub = pkg / "__init__.pyi"
    assert stub.is_file(), list(pkg.iterdir())
    assert (pkg / "py.typed").is_file()
    tree = ast.parse(stub.read_text())
    names = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    assert set(PUBLIC) <= names
    assert isinstance(indentify.__version__, str)


def test_make_map_writes_a_synthetic_map_that_identifies(tmp_path):
    m = indentify.make_map(tmp_path / "map", n=3, noise=0.0, coarse=True)
    assert pathlib.Path(m["manifest"]).is_file() and pathlib.Path(m["base"]).is_file()
    assert len(m["indents"]) == 9
    assert {i["phase"] for i in m["indents"]} == {"A", "B"}
    assert m["phases"]["A"] == {"E": 20000.0, "eta": 30000.0}
    centre = next(i for i in m["indents"] if i["id"] == "p01_01")
    assert centre["phase"] == "B"
    r = indentify.identify(m["base"], data=centre["data"])
    assert r.converged
    assert r.params["E"] == pytest.approx(m["phases"]["B"]["E"], rel=1e-3)
    with pytest.raises(indentify.ConfigError, match="n >= 1"):
        indentify.make_map(tmp_path / "empty", n=0)
    with pytest.raises(TypeError):
        indentify.make_map(["not", "a", "path"])


def test_the_stub_lets_a_type_checker_catch_wrong_calls(tmp_path):
    if os.environ.get("INDENTIFY_REQUIRE_MYPY") == "1":
        # python/run-tests.sh installs mypy: this test must run there, never skip
        import mypy.api as api
    else:
        api = pytest.importorskip("mypy.api", reason="mypy is not installed")
    probe = tmp_path / "probe.py"
    probe.write_text(
        '"""A probe."""\n'
        "import indentify\n"
        'r = indentify.identify("x.ron", sets={"law.E": 1}, progress=print)\n'
        "reveal_type(r.params)\n"
        "indentify.simulate(config=1.5j)\n"
        'indentify.read_record("a.TXT", test="2")\n'
    )
    out, _, status = api.run([str(probe), "--no-incremental", "--cache-dir", str(tmp_path / "cache")])
    assert status == 1, out
    assert 'Revealed type is "dict[str, float]"' in out
    assert 'Argument "config" to "simulate" has incompatible type "complex"' in out
    assert 'Argument "test" to "read_record" has incompatible type "str"' in out
