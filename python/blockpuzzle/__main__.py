"""``blockpuzzle`` / ``python -m blockpuzzle``: the command line of the package.

The Rust command line's own commands and flags, those that need no libtorch: ``envs``, ``info``,
``rollout``, ``render``, ``eval`` (``--suite`` included), ``demos``, ``zoo list|check|evaluate``,
``results``, ``task check|generate``, ``table`` and ``scene``, on the package's engine (MuJoCo 3.11.0). Training
(``train``, ``bench``, ``plot``, ``report``, ``align``, ``zoo export``) is in the Rust command line
(``cargo run --release -- train ...``, docs/training.md); asked for here, they are named as such.
"""

from __future__ import annotations

import signal
import sys

from . import _native  # the package (and with it the engine check) is imported by now

#: Commands of the Rust command line that the package does not have (they need libtorch or plotting):
#: the core's list (``cli::TRAINING_COMMANDS``), e.g. ``train``, ``zoo export``.
RUST_ONLY = tuple(_native.training_commands())


def main(argv: list[str] | None = None) -> int:
    """Runs the command line on ``argv`` (default: ``sys.argv[1:]``) and returns its exit status."""
    args = sys.argv[1:] if argv is None else list(argv)
    words = [a for a in args if not a.startswith("-")][:2]
    what = next((c for c in RUST_ONLY if words[:len(c.split())] == c.split()), None)
    if what is not None:
        print(f"error: `blockpuzzle {what}` is in the Rust command line, not in the Python package (it needs "
              f"libtorch): from a checkout, `cargo run --release -- {what} ...` (docs/training.md)", file=sys.stderr)
        return 2
    # As the Rust binary: Ctrl-C stops the command, and a closed pipe ends it quietly.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    import os  # noqa: PLC0415

    from . import zoo  # noqa: PLC0415

    # Zoo names are the package's entries unless $BLOCKPUZZLE_ZOO names another folder.
    os.environ.setdefault("BLOCKPUZZLE_ZOO", str(zoo.FOLDER))

    sys.stdout.flush()
    return _native.cli(["blockpuzzle", *args])


if __name__ == "__main__":
    sys.exit(main())
