"""Help texts that explain themselves (issue 14): every option with its default, and examples.

Shared by the ``omsd`` command line (:mod:`omsd.cli`) and ``omsd ctl`` (:mod:`omsd.ctl`).
"""

from __future__ import annotations

import argparse
import textwrap


class HelpFormatter(argparse.HelpFormatter):
    """Help with every option's default: said in its help text, or added here (``(default:
    off)`` for a flag, ``(default: X)`` for a value argparse knows). The description and the
    epilog are paragraphs (blank-line separated) wrapped to the terminal, except a paragraph
    with indented lines (the examples), which is kept as written."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        paragraphs = []
        for paragraph in text.split("\n\n"):
            lines = paragraph.splitlines()
            if any(line.startswith("  ") for line in lines):
                paragraphs.append("\n".join(indent + line for line in lines))
            else:
                paragraphs.append(
                    textwrap.fill(
                        " ".join(paragraph.split()),
                        width,
                        initial_indent=indent,
                        subsequent_indent=indent,
                    )
                )
        return "\n\n".join(paragraphs)

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if "default" in text or action.default is argparse.SUPPRESS:
            return text
        if isinstance(action, argparse._StoreTrueAction):
            return f"{text} (default: off)"
        if action.default not in (None, [], False) and action.option_strings:
            return f"{text} (default: %(default)s)"
        return text


def examples(*lines: tuple[str, str]) -> str:
    """An epilog: ``examples:``, then each command with what it does, aligned."""
    width = max(len(command) for command, _ in lines)
    body = "\n".join(f"  {command.ljust(width)}  # {what}" for command, what in lines)
    return f"examples:\n{body}"


__all__ = ["HelpFormatter", "examples"]
