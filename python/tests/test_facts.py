"""Issue 75: one source of truth. The facts the Rust core defines (``_native.facts()``) and the pins
pyproject.toml holds are read, not written again by hand in the package."""

import json
import pathlib
import re
import subprocess
import sys

import blockpuzzle
from blockpuzzle import _native, evaluation, zoo

PACKAGE = pathlib.Path(blockpuzzle.__file__).resolve().parent


def test_the_package_uses_the_cores_facts():
    f = _native.facts()
    assert evaluation.OUTCOMES == tuple(f["outcomes"]) and evaluation.OUTCOMES[0] == "success"
    assert evaluation.COLOURS == tuple(f["colours"]) == ("red", "blue", "green", "grey")
    assert zoo.FORMATS == tuple(f["zoo_formats"]) and f["zoo_format"] == zoo.FORMATS[-1]
    assert (zoo.COLOUR_FEATURE, zoo.ENTITY_FEATURES) == (f["colour_feature"], f["entity_features"])
    # The pins are pyproject.toml's, and the engine the extension runs is the pinned one.
    assert blockpuzzle.MUJOCO_PIN == _native.mujoco_version() and blockpuzzle.MUJOCO_PIN in f["engines"]
    assert re.fullmatch(r"\d+\.\d+\.\d+", blockpuzzle.GYMNASIUM_ROBOTICS_PIN)


def test_zoo_py_on_its_own_reads_the_format_as_the_core_defines_it():
    """zoo.py runs without the extension (a reader to copy): it reads the core's facts from facts.json
    beside it, the very document ``_native.facts()`` gives (the core's tests write and check the file)."""
    assert json.loads((PACKAGE / "facts.json").read_text()) == _native.facts()
    assert sorted(_native.facts()["tasks"]) == sorted(blockpuzzle.env_ids())
    code = ("import sys, importlib.util, json; sys.modules['blockpuzzle'] = None; "
            f"spec = importlib.util.spec_from_file_location('z', {str(PACKAGE / 'zoo.py')!r}); "
            "z = importlib.util.module_from_spec(spec); spec.loader.exec_module(z); "
            "print(json.dumps([list(z.FORMATS), z.COLOUR_FEATURE, z.ENTITY_FEATURES]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    f = _native.facts()
    assert out.strip() == f'[{list(f["zoo_formats"])!r}, {f["colour_feature"]}, {f["entity_features"]}]'.replace("'", '"')


def test_no_fact_is_written_again_in_the_package():
    """Each fact's value, as a literal in the package's source, is a second copy."""
    f = _native.facts()
    literals = {
        "the MuJoCo pin": f'"{blockpuzzle.MUJOCO_PIN}"',
        "the gymnasium-robotics pin": f'"{blockpuzzle.GYMNASIUM_ROBOTICS_PIN}"',
        "a zoo format": '"blockpuzzle-zoo/',
        "the outcome names": ", ".join(f'"{o}"' for o in f["outcomes"][2:5]),
        "the colour order": ", ".join(f'"{c}"' for c in f["colours"][:3]),
        "the colour order (indices)": "_RED, _BLUE",
    }
    features = re.compile(r"^\s*[A-Z_]*FEATURES?\s*(:\s*int)?\s*=\s*\d", re.M)
    found = []
    for path in sorted(PACKAGE.glob("*.py")):
        text = path.read_text()
        found += [f"{path.name}: {what}" for what, lit in literals.items() if lit in text]
        found += [f"{path.name}: {m.group(0).strip()}" for m in features.finditer(text)]
    assert not found, f"facts written by hand (read them from _native.facts() or the package metadata): {found}"
