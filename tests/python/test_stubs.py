"""The stubs (__init__.pyi) declare the public API as the module defines it: every public
name, and the parameters of every public function and method, in the same order."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import aperture

STUBS = Path(__file__).resolve().parents[2] / "python" / "aperture" / "__init__.pyi"


def stub_tree() -> ast.Module:
    return ast.parse(STUBS.read_text())


def stub_parameters(fn: ast.FunctionDef) -> list[str]:
    a = fn.args
    names = [p.arg for p in a.posonlyargs + a.args]
    names += [a.vararg.arg] if a.vararg else []
    names += [p.arg for p in a.kwonlyargs] + ([a.kwarg.arg] if a.kwarg else [])
    return [n for n in names if n != "self"]


def test_every_public_name_has_a_stub() -> None:
    declared = {n.name for n in stub_tree().body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    declared |= {t.id for n in stub_tree().body if isinstance(n, ast.AnnAssign) for t in [n.target] if isinstance(t, ast.Name)}
    assert set(aperture.__all__) <= declared, set(aperture.__all__) - declared


def test_python_functions_match_their_stubs() -> None:
    tree = stub_tree()
    functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    for name in ("load_cameras", "read_exr", "read", "write"):
        real = [p for p in inspect.signature(getattr(aperture, name)).parameters]
        assert stub_parameters(functions[name]) == real, name
    scene = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Scene")
    methods = {n.name: n for n in scene.body if isinstance(n, ast.FunctionDef)}
    for name in ("__init__", "render", "render_iter", "face_visibility", "point_visibility"):
        real = [p for p in inspect.signature(getattr(aperture.Scene, name)).parameters if p != "self"]
        assert stub_parameters(methods[name]) == real, name
    assert aperture.__version__ and aperture.Scene.render.__doc__ and aperture.Camera.__doc__
