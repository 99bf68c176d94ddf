"""The one error path of every command line of the project.

Bad input - a malformed option, a value out of range, a config override the schema refuses, a
missing file - ends the command with one line on stderr, ``<prog>: error: <what is wrong>``,
and exit status 2: argparse's own errors through :class:`ArgumentParser`, and the
``ValueError``/``TypeError``/... that validation raises through :func:`user_errors`.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Callable, Iterator
from typing import NoReturn

__all__ = ["USER_ERRORS", "ArgumentParser", "UsageError", "at_least", "int_like", "user_errors"]

#: what validation raises for bad input (a programming error raises something else and keeps
#: its traceback)
USER_ERRORS: tuple[type[Exception], ...] = (
    ValueError,
    TypeError,
    FileNotFoundError,
    FileExistsError,
)


class UsageError(SystemExit):
    """The exit of a command after bad input: status 2; ``str()`` is the message (without the
    ``prog: error:`` prefix of the line on stderr), so callers and tests can read it."""

    def __init__(self, message: str) -> None:
        super().__init__(2)
        self.message = message

    def __str__(self) -> str:
        return self.message


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser with the project's error: one line on stderr, ``prog: error:
    message``, then :class:`UsageError` (exit status 2; no usage block, ``--help`` shows it)."""

    def error(self, message: str) -> NoReturn:
        self._print_message(f"{self.prog}: error: {message}\n", sys.stderr)
        raise UsageError(message)


@contextlib.contextmanager
def user_errors(parser: argparse.ArgumentParser, *also: type[BaseException]) -> Iterator[None]:
    """Bad input raised inside (:data:`USER_ERRORS`, and ``also``) ends in
    ``parser.error`` with the exception's message."""
    try:
        yield
    except (*USER_ERRORS, *also) as e:
        parser.error(str(e))


def at_least(lo: int) -> Callable[[str], int]:
    """An argparse ``type`` for integers ``>= lo``: ``--workers 0`` is refused by argparse,
    naming the option and the value."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if value < lo:
            raise argparse.ArgumentTypeError(f"{value} is invalid: must be >= {lo}")
        return value

    parse.__name__ = f"integer >= {lo}"
    return parse


def int_like(text: str) -> int:
    """An argparse ``type`` for integers also written as ``2e7`` or ``20_000_000``."""
    try:
        v = float(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not v.is_integer():
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer")
    return int(v)
