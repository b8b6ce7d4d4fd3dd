"""Every Python code block of the README and the docs runs as written, with the installed package.

A block is run in a fresh namespace in an empty folder, so it must create every file it reads: a
block that refers to a file it never creates fails (a ``FileNotFoundError`` while it runs, or a
relative file name in one of its strings that does not exist once it has run). A block that is not
meant to run alone says so on the line above its fence: ``<!-- fragment: why -->``; the test checks
that every such mark gives a reason. The Rust test ``tests/it/docs.rs`` checks the shell blocks (each
command line parses; make targets and scripts exist) and the TOML blocks (valid task and suite
files); ``cargo test`` runs the README's Rust block (a doctest).
"""

from __future__ import annotations

import ast
import pathlib
import re

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


#: A string that names a file relative to the block's folder: what a block must create if it names it.
FILE_NAME = re.compile(r"^[\w.-]+(/[\w.-]+)*\.(toml|json|jsonl|safetensors|csv|png|gif|npz|npy|txt|h5|hdf5|zip|pkl)$")


def file_names(code: str) -> list[str]:
    """The relative file names in the block's string literals (not its comments)."""
    return sorted({n.value for n in ast.walk(ast.parse(code))
                   if isinstance(n, ast.Constant) and isinstance(n.value, str) and FILE_NAME.match(n.value)})


def run_block(code: str, where: str, folder: pathlib.Path) -> None:
    """Runs a block as a script would run, in ``folder`` (empty), and checks that every file it names
    exists there once it has run."""
    fix = "create the file in the block, or mark the block <!-- fragment: why --> on the line above its fence"
    # Run as a script would be: its own globals, its name __main__, its file named in tracebacks.
    compiled = compile(code, where, "exec")
    namespace = {"__name__": "__main__"}
    try:
        exec(compiled, namespace)  # noqa: S102 (the repository's own documentation)
    except FileNotFoundError as e:
        pytest.fail(f"{where}: the block reads a file it never creates ({e}); {fix}")
    finally:
        for env in [v for v in namespace.values() if hasattr(v, "close") and hasattr(v, "reset")]:
            env.close()
    missing = [name for name in file_names(code) if not (folder / name).exists()]
    if missing:
        pytest.fail(f"{where}: the block names {', '.join(missing)} but never creates it; {fix}")


@pytest.mark.parametrize(("path", "line", "code"), PYTHON)
def test_python_block_runs_as_written(path, line, code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert not list(tmp_path.iterdir())
    run_block(code, f"{path.relative_to(ROOT)}:{line}", tmp_path)


@pytest.mark.parametrize("code", [
    # docs/python.md's third block before issue 60: a task file the reader was to bring.
    'import blockpuzzle\nenv = blockpuzzle.make_task("my-task.toml")\n',
    # A name the block never reads: still a file the reader does not have.
    'import blockpuzzle\nsuite = "my-suite.toml"\n',
])
def test_a_block_that_refers_to_a_file_it_never_creates_fails(code, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(pytest.fail.Exception, match=r"my-(task|suite).toml.*create the file in the block, or mark"):
        run_block(code, "example.md:1", tmp_path)
    (tmp_path / "ok.toml").write_text("")
    run_block('open("ok.toml").read()  # "mentioned.toml" in a comment is not a file name\n', "example.md:1", tmp_path)
