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


def test_the_public_functions_and_the_stub_are_fully_typed():
    import inspect

    from blockpuzzle import datasets, sb3, zoo

    public = [getattr(blockpuzzle, n) for n in blockpuzzle.__all__ if inspect.isfunction(getattr(blockpuzzle, n))]
    public += [datasets.load_demos, datasets.record_demos, datasets.to_minari, zoo.load, zoo.names,
               zoo.read_safetensors, *[f for n, f in vars(sb3.SB3VecEnv).items() if inspect.isfunction(f)
                                       and (not n.startswith("_") or n == "__init__")]]
    names = {f.__name__ for f in public}
    assert {"env_ids", "generate_tasks", "load_demos", "make_task", "make_vec", "evaluate"} <= names, names
    for f in public:
        sig = inspect.signature(f)
        untyped = [p.name for p in sig.parameters.values()
                   if p.annotation is inspect.Parameter.empty and p.name != "self"
                   and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
        assert not untyped, (f.__qualname__, untyped)
        assert sig.return_annotation is not inspect.Signature.empty, f.__qualname__
    stub = ast.parse((pathlib.Path(blockpuzzle.__file__).parent / "_native.pyi").read_text())
    for node in ast.walk(stub):
        if isinstance(node, ast.FunctionDef):
            args = [a for a in node.args.args + node.args.kwonlyargs if a.arg != "self"]
            assert all(a.annotation is not None for a in args) and node.returns is not None, node.name
