"""What the commands of the application layer share: the progress bar, the
lazy import of peer libraries, argparse value checks and the help formatter.

Library code never prints; the long loops of the demo, the benchmarks and the
experiments take a ``progress`` callable (default :func:`no_progress`, silent)
and the command line passes :func:`progress_bar`.
"""

from __future__ import annotations

import argparse
import importlib
import math
import re
import sys
from types import ModuleType
from typing import Callable, Iterable, Optional, TypeVar

__all__ = ["Progress", "no_progress", "progress_bar", "write_line", "MissingPeerError",
           "import_peer", "positive_int", "non_negative_int", "positive_float", "non_negative_float",
           "positive_int_list", "add_count_and_seed", "HelpFormatter", "plain_text"]

T = TypeVar("T")

#: ``progress(iterable, total=None, desc=None) -> iterable``: wraps a loop
Progress = Callable[..., Iterable]


def no_progress(iterable: Iterable[T], total: Optional[int] = None,
                desc: Optional[str] = None) -> Iterable[T]:
    """The silent default of every loop that accepts a ``progress`` callable."""
    return iterable


def progress_bar(iterable: Iterable[T], total: Optional[int] = None,
                 desc: Optional[str] = None) -> Iterable[T]:
    """A tqdm bar on stderr while the loop runs, removed when it ends.

    Shown only when stderr is a terminal, so logs and pipes get no carriage
    returns; stdout (the tables the commands print) is never touched.
    """
    from tqdm import tqdm  # a runtime dependency, imported when a command runs

    stream = sys.stderr
    return tqdm(iterable, total=total, desc=desc, file=stream, leave=False,
                disable=not (hasattr(stream, "isatty") and stream.isatty()))


def write_line(text: str = "") -> None:
    """Print a line to stdout without breaking a progress bar on stderr (for
    loops that print as they go)."""
    from tqdm import tqdm

    tqdm.write(text, file=sys.stdout)


class MissingPeerError(RuntimeError):
    """A peer library an experiment or benchmark compares against is not installed.

    The message says what needs it and how to install it; the command line
    prints it and exits with code 2.
    """


def import_peer(module: str, needed_by: str, pip_name: Optional[str] = None) -> ModuleType:
    """Import ``module`` or raise :class:`MissingPeerError` naming ``needed_by``."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingPeerError(f"{needed_by} needs {module}: pip install "
                               f"{pip_name or module}") from None


# ---------------------------------------------------------------- argparse types
# argparse turns the ValueError / ArgumentTypeError of a type= callable into a
# usage error (exit code 2) instead of a traceback deep in the computation.

def _number(text: str, kind: type, lower: float, strict: bool, what: str):
    """``kind(text)``, finite and above ``lower`` (or equal, unless ``strict``)."""
    try:
        value = kind(text)
    except ValueError:
        value = None
    if (value is None or (kind is float and not math.isfinite(value))
            or value < lower or (strict and value == lower)):
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1 (counts of trials, problems, runs)."""
    return _number(text, int, 1, False, "a positive integer")


def non_negative_int(text: str) -> int:
    """An integer >= 0 (random seeds: numpy refuses negative ones)."""
    return _number(text, int, 0, False, "a non-negative integer")


def positive_float(text: str) -> float:
    """A finite number > 0 (time budgets, thresholds)."""
    return _number(text, float, 0.0, True, "a positive number")


def non_negative_float(text: str) -> float:
    """A finite number >= 0 (noise levels)."""
    return _number(text, float, 0.0, False, "a non-negative number")


def fraction(text: str) -> float:
    """A number in [0, 1] (shares of correspondences)."""
    value = non_negative_float(text)
    if value > 1.0:
        raise argparse.ArgumentTypeError(f"expected a fraction in [0, 1], got {text!r}")
    return value


def positive_int_list(text: str) -> tuple[int, ...]:
    """A comma-separated list of integers >= 1, e.g. ``17,100,1000``."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = tuple(int(p) for p in parts)
    except ValueError:
        values = ()
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(
            f"expected a comma-separated list of positive integers, got {text!r}")
    return values


def add_count_and_seed(ap: argparse.ArgumentParser, option: str, default: int,
                       what: str) -> None:
    """The two options of most synthetic experiments: how many (``option``, a
    positive integer) and the random seed."""
    ap.add_argument(option, type=positive_int, default=default, help=what)
    ap.add_argument("--seed", type=non_negative_int, default=0, help="random seed")


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter,
                    argparse.RawDescriptionHelpFormatter):
    """Descriptions as written (paragraphs and lists kept), every option's
    default appended to its help, except where the help states it itself
    (default None: it depends on other options; or the help already says
    "default", which argparse would repeat as a Python repr)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        if action.default is None or "default" in (action.help or ""):
            return action.help or ""
        return super()._get_help_string(action)


def plain_text(doc: Optional[str]) -> str:
    """A module docstring as command-line help: the reStructuredText markup
    (double backticks, roles such as :func:`x`) removed."""
    text = re.sub(r":[a-z]+:`~?([^`]*)`", r"\1", doc or "")
    return text.replace("``", "").strip()
