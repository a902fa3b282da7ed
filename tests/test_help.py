"""The command line explains itself (issue 14): ``omsd --help`` and every subcommand's help have a
usage line, every option with its default, and two or three examples; ``--tcp`` without ``--pty``
replacing the default pty is said in the help."""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from collections.abc import Iterator

import pytest
from daemon.process import daemon_env, run_omsd

from omsd import cli, ctl
from omsd.helptext import HelpFormatter


def _subparsers(parser: argparse.ArgumentParser) -> Iterator[argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):  # aliases appear once
                yield sub
                yield from _subparsers(sub)


def _all() -> list[argparse.ArgumentParser]:
    top = cli._parser()
    parsers = [top, *_subparsers(top), ctl.parser(), *_subparsers(ctl.parser())]
    # "omsd ctl" is listed in omsd's help only; its own parser is omsd.ctl's
    return [p for p in parsers if p.prog != "omsd ctl" or p.add_help]


PARSERS = {p.prog: p for p in _all()}


def test_every_command_is_covered() -> None:
    assert {"omsd", "omsd models", "omsd commands", "omsd console", "omsd ctl"} <= set(PARSERS)
    assert {"omsd ctl limit", "omsd ctl time step", "omsd ctl wait done"} <= set(PARSERS)


@pytest.mark.parametrize("prog", list(PARSERS))
def test_usage_every_default_and_examples(prog: str) -> None:
    parser = PARSERS[prog]
    text = parser.format_help()
    assert text.startswith(f"usage: {prog}"), text[:80]
    formatter = HelpFormatter(prog)
    for action in parser._actions:
        if (
            not action.option_strings
            or action.required  # (a required option has no default)
            or isinstance(action, argparse._HelpAction | argparse._VersionAction)
        ):
            continue
        helped = formatter._get_help_string(action)
        assert "default" in helped, f"{prog} {action.option_strings[0]}: no default in {helped!r}"
    for action in parser._actions:  # positional arguments with a default say it too
        positional = not action.option_strings and action.nargs == "?"
        if positional and action.default not in (None, argparse.SUPPRESS):
            assert "default" in (action.help or ""), (prog, action.dest)
    assert parser.epilog is not None and parser.epilog.startswith("examples:\n"), prog
    examples = re.findall(r"^  (omsd|printf) .*  # ", parser.epilog, re.M)
    assert 2 <= len(examples) <= 3, (prog, parser.epilog)


def test_the_help_runs_and_says_tcp_alone_means_no_pty() -> None:
    done = run_omsd("--help")
    assert done.returncode == 0 and done.stderr == ""
    text = " ".join(done.stdout.split())
    assert "Given without --pty, it replaces the defaults: no pty" in text
    assert "(default: 127.0.0.1:7048, with the default pty)" in text
    assert "(default: PC48-4E;" in text and "(default: off)" in text
    assert "exit status: 0 stopped; 2 not started" in text
    for command in ("models", "commands", "console", "ctl"):
        assert run_omsd(command, "--help").returncode == 0


def test_help_lines_fit_a_terminal() -> None:
    """The examples, kept as written, fit 80 columns; the rest is wrapped to the terminal."""
    for prog, parser in PARSERS.items():
        for line in (parser.epilog or "").splitlines():
            assert len(line) <= 80, (prog, line)
    for columns in ("60", "100"):
        done = subprocess.run(
            [sys.executable, "-m", "omsd", "--help"],
            capture_output=True,
            text=True,
            env={**daemon_env(), "COLUMNS": columns},
            check=True,
        )
        examples = done.stdout.index("examples:")
        for line in done.stdout[:examples].splitlines():
            if not line.startswith("usage:"):
                assert len(line) <= int(columns), line
