# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""The one reader of fourws configuration YAML (vehicles, maneuvers, scenarios, studies, node
parameter files).

PyYAML's ``safe_load`` reads YAML 1.1 and trusts its input; a configuration reader must not:

* **Numbers as YAML 1.2 reads them.** ``1e-3``, ``1E5`` and ``2.0e3`` are floats (YAML 1.1
  reads them as strings, so ``mass_kg: 1e3`` was refused as "not a number" and a string field
  took them silently). Dates are not special (``2024-01-01`` stays a string, as in YAML 1.2's
  core schema). Booleans keep the YAML 1.1 words (``on``/``off``/``yes``/``no``), as the ROS 2
  parameter-file parser reads them.
* **No duplicate keys.** YAML forbids them; PyYAML keeps the last value without a word. Here a
  duplicate is an error naming the key, both lines and the file.
* **Mapping keys are strings.** Every fourws field name is one; ``1: x`` or ``null: x`` is an
  error, not a key of another type that later breaks a sort or a lookup.
* **Bounded size.** At most :data:`MAX_FILE_BYTES` bytes, :data:`MAX_DEPTH` levels of nesting,
  :data:`MAX_ALIASES` alias uses and :data:`MAX_NODES` nodes once aliases are expanded (a
  1.4 kB file of nested anchors, "billion laughs", expands to 10^9 nodes); recursive aliases
  are refused.
* **UTF-8 text only.** Binary files, UTF-16 and Latin-1 files are refused with one line (not a
  ``UnicodeDecodeError`` traceback); a UTF-8 byte-order mark is accepted.

Every refusal is a :class:`~fourws_sim.errors.ParameterError` whose one-line message names the
file and, where there is one, the key and line.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from fourws_sim.errors import ParameterError

#: Largest configuration file read, bytes (the shipped files are below 10 kB).
MAX_FILE_BYTES = 1 << 20
#: Deepest nesting of mappings and sequences (the shipped files nest at most 5 deep).
MAX_DEPTH = 32
#: Most alias uses (``*name``) in one file (the shipped files use none).
MAX_ALIASES = 100
#: Most nodes of a document with every alias expanded (the shipped files have < 300).
MAX_NODES = 20_000

_FLOAT_TAG = "tag:yaml.org,2002:float"
_MERGE_TAG = "tag:yaml.org,2002:merge"
_STR_TAG = "tag:yaml.org,2002:str"
#: YAML 1.2 core-schema floats PyYAML's 1.1 pattern misses: an exponent without a dot
#: (``1e-3``, ``1E5``) or without a sign (``2.0e3``, ``.5e2``).
_FLOAT_12 = re.compile(r"""^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$""")


class _LimitError(yaml.YAMLError):
    """What the strict reader refuses beyond YAML syntax: a limit exceeded, a duplicate or
    non-string key (the problem, where, and the key concerned if any)."""

    def __init__(self, problem: str, mark: Any = None, key: str | None = None) -> None:
        super().__init__(problem)
        self.problem = problem
        self.problem_mark = mark
        self.key = key


def _line(mark: Any) -> str:
    return f"line {mark.line + 1}" if mark is not None else "?"


class StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` with YAML 1.2 floats, no timestamps, no duplicate or non-string keys,
    and bounded nesting and aliases (see the module docstring)."""

    yaml_implicit_resolvers = {
        first: [(tag, regexp) for tag, regexp in resolvers
                if tag != "tag:yaml.org,2002:timestamp"]
        for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()}

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._depth = 0
        self._aliases = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise _LimitError(f"more than {MAX_ALIASES} aliases", self.peek_event().start_mark)
            return super().compose_node(parent, index)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise _LimitError(f"nested deeper than {MAX_DEPTH} levels",
                                  self.peek_event().start_mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node: Any, deep: bool = False) -> Any:
        if isinstance(node, MappingNode):
            seen: dict[str, Any] = {}
            for key_node, _value in node.value:
                if key_node.tag == _MERGE_TAG:
                    continue
                if not isinstance(key_node, ScalarNode):
                    raise _LimitError("a mapping key is a sequence or mapping, not a name",
                                      key_node.start_mark)
                if key_node.tag != _STR_TAG:
                    raise _LimitError(f"mapping key {key_node.value[:40]!r} is not a string "
                                      "(quote it)", key_node.start_mark)
                if key_node.value in seen:
                    raise _LimitError(f"duplicate key at {_line(key_node.start_mark)} (first at "
                                      f"{_line(seen[key_node.value])})", None, key_node.value)
                seen[key_node.value] = key_node.start_mark
        return super().construct_mapping(node, deep=deep)


StrictLoader.add_implicit_resolver(_FLOAT_TAG, _FLOAT_12, list("-+0123456789."))


def _expanded_size(root: Node) -> int:
    """Node count with every alias expanded (shared nodes counted at each use); raises
    :class:`_LimitError` on a recursive alias or above :data:`MAX_NODES`."""
    sizes: dict[int, int] = {}
    open_nodes: set[int] = set()

    def size(node: Node) -> int:
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in open_nodes:
            raise _LimitError("recursive alias (a node contains itself)", node.start_mark)
        open_nodes.add(key)
        total = 1
        if isinstance(node, SequenceNode):
            total += sum(size(child) for child in node.value)
        elif isinstance(node, MappingNode):
            total += sum(size(k) + size(v) for k, v in node.value)
        open_nodes.discard(key)
        if total > MAX_NODES:
            raise _LimitError(f"more than {MAX_NODES} values once aliases are expanded",
                              node.start_mark)
        sizes[key] = total
        return total

    return size(root)


def _decode(data: bytes, source: str) -> str:
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise ParameterError("<file>", "is UTF-16 text; fourws reads UTF-8 (save it as UTF-8)",
                             source)
    if b"\x00" in data:
        raise ParameterError("<file>", "is not a text file (it contains NUL bytes)", source)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ParameterError("<file>", f"is not UTF-8 text (byte 0x{data[exc.start]:02x} at "
                             f"offset {exc.start}); fourws reads UTF-8 YAML", source) from None


def parse_yaml(text: str | bytes, source: str = "<text>") -> Any:
    """Parse one YAML document strictly (see the module docstring).

    Parameters
    ----------
    text : str or bytes
        The document (bytes are decoded as UTF-8).
    source : str
        Where it came from (named in errors).

    Raises
    ------
    ParameterError
        Not UTF-8, not valid YAML, a duplicate or non-string key, or over a size limit; the
        field is the key concerned or ``<file>``.
    """
    if isinstance(text, bytes):
        if len(text) > MAX_FILE_BYTES:
            raise ParameterError("<file>", f"larger than {MAX_FILE_BYTES} bytes", source)
        text = _decode(text, source)
    elif len(text) > MAX_FILE_BYTES:
        raise ParameterError("<file>", f"larger than {MAX_FILE_BYTES} bytes", source)
    loader = None
    try:
        loader = StrictLoader(text)
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node)
        return loader.construct_document(node)
    except _LimitError as exc:
        where = f" ({_line(exc.problem_mark)})" if exc.problem_mark is not None else ""
        raise ParameterError(exc.key if exc.key is not None else "<file>",
                             f"{exc.problem}{where}", source) from None
    except yaml.reader.ReaderError as exc:
        raise ParameterError("<file>", f"not valid YAML: character #x{exc.character:04x} at "
                             f"offset {exc.position} is not allowed", source) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        problem = " ".join(str(exc.problem or exc.context or "syntax error").split())
        where = f" at {_line(mark)}, column {mark.column + 1}" if mark is not None else ""
        raise ParameterError("<file>", f"not valid YAML: {problem}{where}", source) from None
    except yaml.YAMLError as exc:
        raise ParameterError("<file>", f"not valid YAML: {' '.join(str(exc).split())}",
                             source) from None
    except (ValueError, OverflowError, TypeError) as exc:
        # an explicit tag with a value it cannot take (``!!float abc``, ``!!int 1.5``)
        raise ParameterError("<file>", f"not valid YAML: {' '.join(str(exc).split())}",
                             source) from None
    except RecursionError:
        raise ParameterError("<file>", "not valid YAML: nested too deeply", source) from None
    finally:
        if loader is not None:
            loader.dispose()


def plain_copy(data: Any) -> Any:
    """A copy of parsed YAML/JSON data: every dict and list copied, other values shared (as
    ``copy.deepcopy`` of such data, many times faster; scalars and strings are immutable)."""
    kind = type(data)
    if kind is dict:
        return {k: plain_copy(v) for k, v in data.items()}
    if kind is list:
        return [plain_copy(v) for v in data]
    return data


def read_config_text(path: str | Path) -> str:
    """The text of a configuration file, checked as :func:`read_yaml` checks it (readable, at
    most :data:`MAX_FILE_BYTES`, UTF-8), for a reader that keeps the text beside the parsed
    data (a study stores its file as given).

    Raises
    ------
    ParameterError
        The file cannot be read, is too large or is not UTF-8 text (field ``<file>``).
    """
    path = Path(path)
    try:
        with open(path, "rb") as stream:
            data = stream.read(MAX_FILE_BYTES + 1)  # bounded even for a FIFO or /dev/zero
    except OSError as exc:
        raise ParameterError("<file>", f"cannot be read ({exc.strerror or exc})",
                             str(path)) from None
    if len(data) > MAX_FILE_BYTES:
        raise ParameterError("<file>", f"larger than {MAX_FILE_BYTES} bytes", str(path))
    return _decode(data, str(path))


def read_yaml(path: str | Path) -> Any:
    """Read and parse a configuration file strictly (:func:`parse_yaml`).

    Raises
    ------
    ParameterError
        The file cannot be read, is larger than :data:`MAX_FILE_BYTES`, is not UTF-8 or not
        valid strict YAML (field ``<file>`` or the key concerned; the file is named).
    """
    return parse_yaml(read_config_text(path), str(path))


__all__ = ["MAX_ALIASES", "MAX_DEPTH", "MAX_FILE_BYTES", "MAX_NODES", "StrictLoader",
           "parse_yaml", "read_config_text", "read_yaml"]
