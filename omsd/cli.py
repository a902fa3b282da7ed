"""The ``omsd`` command line."""

from __future__ import annotations

import argparse
import sys

from omsd import __version__
from omsd.models import MODELS, UnknownModel, get_model

DEFAULT_MODEL = "PC48-4E"


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="omsd",
        description="Virtual Oregon Micro Systems motion controllers.",
    )
    p.add_argument("--version", action="version", version=f"omsd {__version__}")
    sub = p.add_subparsers(dest="command")
    console = sub.add_parser("console", help="talk to one emulated board on this terminal")
    console.add_argument("--board", default=DEFAULT_MODEL, help="model, e.g. PC48-8E")
    sub.add_parser("models", help="list the board personalities")
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "models":
        for model in MODELS.values():
            print(f"{model.name:<10} {model.description}")
        return 0
    name = getattr(args, "board", DEFAULT_MODEL)
    try:
        model = get_model(name)
    except UnknownModel as exc:
        print(f"omsd: {exc}", file=sys.stderr)
        return 2
    from omsd.console import main as console_main

    return console_main(model)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
