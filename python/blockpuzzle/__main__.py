"""``blockpuzzle`` / ``python -m blockpuzzle``: the command line of the package.

The Rust command line's own commands and flags, those that need no libtorch: ``envs``, ``info``,
``rollout``, ``render``, ``eval`` (``--suite`` included), ``zoo list|check|evaluate``, ``results``,
``task check`` and ``scene``, on the package's engine (MuJoCo 3.11.0). Training (``train``,
``table``, ``bench``, ``plot``, ``report``, ``align``, ``zoo export``) is in the Rust command line
(``cargo run --release -- train ...``, docs/training.md); asked for here, they are named as such.
"""

from __future__ import annotations

import signal
import sys

#: Commands of the Rust command line that the package does not have (they need libtorch or plotting).
RUST_ONLY = ("train", "table", "bench", "plot", "report", "align")


def main(argv: list[str] | None = None) -> int:
    """Runs the command line on ``argv`` (default: ``sys.argv[1:]``) and returns its exit status."""
    args = sys.argv[1:] if argv is None else list(argv)
    if args and args[0] in RUST_ONLY or args[:2] == ["zoo", "export"]:
        what = " ".join(args[:2]) if args[0] == "zoo" else args[0]
        print(f"error: `blockpuzzle {what}` is in the Rust command line, not in the Python package (it needs "
              f"libtorch): from a checkout, `cargo run --release -- {what} ...` (docs/training.md)", file=sys.stderr)
        return 2
    # As the Rust binary: Ctrl-C stops the command, and a closed pipe ends it quietly.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    import os  # noqa: PLC0415

    from . import _native, zoo  # noqa: PLC0415 (importing the package checks the engine and the Fetch files)

    # Zoo names are the package's entries unless $BLOCKPUZZLE_ZOO names another folder.
    os.environ.setdefault("BLOCKPUZZLE_ZOO", str(zoo.FOLDER))

    sys.stdout.flush()
    return _native.cli(["blockpuzzle", *args])


if __name__ == "__main__":
    sys.exit(main())
