"""Every Python code block of the README and the docs runs as written, with the installed package.

A block is run in a fresh namespace in an empty folder (``my-task.toml`` there: a copy of
``tasks/BlocksTouch-v0.toml``, the task file the docs ask the reader to bring). A block that is not
meant to run alone says so on the line above its fence: ``<!-- fragment: why -->``; the test checks
that every such mark gives a reason. The Rust test ``tests/it/docs.rs`` checks the shell blocks (each
command line parses; make targets and scripts exist) and the TOML blocks (valid task and suite
files); ``cargo test`` runs the README's Rust block (a doctest).
"""

from __future__ import annotations

import os
import pathlib
import re
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "python" / "README.md",
        ROOT / "zoo" / "README.md"]
FENCE = re.compile(r"^(\s*)```(\S*)")
FRAGMENT = re.compile(r"^\s*<!--\s*fragment(.*)-->\s*$")


def blocks(path: pathlib.Path):
    """``(language, first line number, code, fragment mark or None)`` of each fenced block."""
    lines = path.read_text().splitlines()
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, lang, start = m.group(1), m.group(2), i + 1
        before = next((lines[k] for k in range(i - 1, -1, -1) if lines[k].strip()), "")
        mark = FRAGMENT.match(before)
        j = i + 1
        while j < len(lines) and not lines[j].strip().startswith("```"):
            j += 1
        code = "\n".join(line[len(indent):] if line.startswith(indent) else line for line in lines[i + 1:j])
        out.append((lang, start, code, mark.group(1).strip(" :") if mark else None))
        i = j + 1
    return out


PYTHON = [pytest.param(p, n, code, id=f"{p.relative_to(ROOT)}:{n}")
          for p in DOCS for lang, n, code, mark in blocks(p) if lang == "python" and mark is None]


def test_the_docs_have_python_blocks_and_every_fragment_says_why():
    assert len(PYTHON) >= 5
    for p in DOCS:
        for lang, n, _, mark in blocks(p):
            assert mark is None or mark, f"{p.relative_to(ROOT)}:{n}: say why the block is a fragment"


@pytest.mark.parametrize(("path", "line", "code"), PYTHON)
def test_python_block_runs_as_written(path, line, code, tmp_path, monkeypatch):
    shutil.copy(ROOT / "tasks" / "BlocksTouch-v0.toml", tmp_path / "my-task.toml")
    monkeypatch.chdir(tmp_path)
    # Run as a script would be: its own globals, its name __main__, its file named in tracebacks.
    compiled = compile(code, f"{path.relative_to(ROOT)}:{line}", "exec")
    namespace = {"__name__": "__main__"}
    exec(compiled, namespace)  # noqa: S102 (the repository's own documentation)
    for env in [v for v in namespace.values() if hasattr(v, "close") and hasattr(v, "reset")]:
        env.close()
