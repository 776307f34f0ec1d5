"""YAML calibration files through PyYAML's safe loader, restricted to plain data.

Kalibr writes its camchain files with PyYAML (``yaml.dump``) and reads them with it, so
PyYAML is the reference reader. On top of ``yaml.SafeLoader`` (which already constructs
nothing but plain Python data: no ``!!python/...`` objects) this loader refuses, while
composing -- before anything is constructed:

* anchors and aliases (``&a`` / ``*a``): a calibration file has no use for them, and
  nested aliases expand exponentially ("billion laughs");
* explicit tags (``!!python/object``, ``!!opencv-matrix``, ``!!str``, ...): the formats
  read here use none, so a tag means a file of another kind;
* nesting deeper than :data:`MAX_DEPTH` (a Kalibr file nests 4 deep; PyYAML's composer
  and constructor recurse, and a deeply nested junk file must be a ``ValueError``, not a
  ``RecursionError``);
* duplicate mapping keys (PyYAML keeps the last one silently).

Every problem is a ``ValueError`` ``"<file>: line <n>: <problem>"``.
"""

from __future__ import annotations

import re
from typing import Any

import yaml
from yaml.composer import ComposerError
from yaml.constructor import ConstructorError

__all__ = ["MAX_DEPTH", "load_yaml"]

MAX_DEPTH = 64


class _PlainDataLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` without anchors, aliases, tags, duplicate keys or deep nesting."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            raise ComposerError(None, None, f"aliases (*{event.anchor}) are not allowed: "
                                f"calibration files have no use for anchors and aliases",
                                event.start_mark)
        if event.anchor is not None:
            raise ComposerError(None, None, f"anchors (&{event.anchor}) are not allowed: "
                                f"calibration files have no use for anchors and aliases",
                                event.start_mark)
        tag = getattr(event, "tag", None)  # None unless the file spells a tag out
        if tag is not None:
            raise ComposerError(None, None, f"tags are not allowed ({tag})", event.start_mark)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise ComposerError(None, None, f"nesting deeper than {MAX_DEPTH} levels",
                                    event.start_mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_object(self, node: Any, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep=deep)
        except ValueError as exc:  # a scalar Python will not convert (an int of 5000 digits)
            raise ConstructorError(None, None, str(exc), node.start_mark) from None

    def construct_mapping(self, node: Any, deep: bool = False) -> dict:
        self.flatten_mapping(node)  # merge keys ("<<") first, as SafeConstructor does
        seen: set = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                repeated = key in seen
            except TypeError:
                continue  # an unhashable key: SafeConstructor reports it
            if repeated:
                raise ConstructorError(None, None, f"duplicate key {key!r}", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


# YAML 1.1 (PyYAML) reads "1e-05" -- an exponent without a '.' -- as a string; YAML 1.2,
# JSON and the subset parser mcgeom used before PyYAML read it as a number, so hand-edited
# files that write it keep loading.
_PlainDataLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


def _describe(exc: yaml.MarkedYAMLError) -> str:
    """``line <n>: <problem> (<context> at line <m>)`` from a PyYAML error."""
    mark = exc.problem_mark or exc.context_mark
    text = exc.problem or exc.context or "malformed YAML"
    notes = []
    if exc.context and exc.problem:
        start = exc.context_mark
        at = f" at line {start.line + 1}" if start is not None and start.line != mark.line else ""
        notes.append(exc.context + at)
    if "<stream end>" in text:
        notes.append("truncated file?")
    if notes:
        text += f" ({'; '.join(notes)})"
    return f"line {mark.line + 1}: {text}" if mark is not None else text


def load_yaml(text: str, where: str) -> Any:
    """The plain data (dict / list / str / int / float / bool / None) of one YAML document.

    Args:
        text: the document.
        where: the file name, for messages.

    Raises:
        ValueError: ``"<where>: line <n>: <problem>"``: a YAML syntax error, an empty
            document, more than one document, or anything :class:`_PlainDataLoader` refuses.
    """
    try:
        loader = _PlainDataLoader(text)  # checks every character first
    except yaml.reader.ReaderError as exc:  # a character YAML does not allow (NUL, ...)
        line = text.count("\n", 0, exc.position) + 1
        code = exc.character if isinstance(exc.character, int) else ord(exc.character)
        raise ValueError(f"{where}: line {line}: character U+{code:04X} is not allowed "
                         f"in YAML") from None
    try:
        node = loader.get_single_node()
        if node is None:
            raise ValueError(f"{where}: empty YAML document")
        return loader.construct_document(node)
    except yaml.MarkedYAMLError as exc:
        raise ValueError(f"{where}: {_describe(exc)}") from None
    finally:
        loader.dispose()
