"""The package carries type information (PEP 561): a ``py.typed`` marker and a stub of the extension
module that names exactly what the module holds."""

import ast
import pathlib

import blockpuzzle
from blockpuzzle import _native


def test_the_package_is_typed_and_the_stub_matches_the_extension():
    folder = pathlib.Path(blockpuzzle.__file__).parent
    assert (folder / "py.typed").is_file()
    stub = ast.parse((folder / "_native.pyi").read_text())
    declared = {}
    for node in stub.body:
        if isinstance(node, ast.ClassDef):
            declared[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef) and n.name != "__init__"}
        elif isinstance(node, ast.FunctionDef):
            declared[node.name] = None
    actual = {n for n in dir(_native) if not n.startswith("__")}
    assert set(declared) == actual, (set(declared) ^ actual)
    for cls, members in declared.items():
        if members is not None:
            have = {m for m in vars(getattr(_native, cls)) if not m.startswith("__")}
            assert members == have, (cls, members ^ have)
