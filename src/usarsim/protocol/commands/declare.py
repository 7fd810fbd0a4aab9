"""Commands declared once: each field of a command's dataclass says how it travels, and both
the parser and the format follow from that.

A field is one of:

* :func:`key`: one ``{Key value}`` segment of a kind of value (:class:`Kind`: text, a
  number, an integer, a truth value, a vector; :func:`choice` narrows one to a set), with
  the other spellings a client may send (``Normalize``, ``Seq``).  Read the first time it
  comes (later ones are ignored, or kept in the command's :func:`rest`), written when it is
  not None.
* :func:`group`: repeated groups of keys, each opened by its first key (DRIVE's
  ``{WheelNumber n} {WheelSpeed v} {WheelSteer a}``, MISPKG's ``{Link n} {Value v}
  [{Order o}]``), declared as a small dataclass of keys.  A group key sent before any group
  is opened is refused, unless the key is declared ``outside="ignore"`` (then the command's
  own key of that name takes it, if it has one); a group missing a key without a default is
  refused when it closes.
* :func:`numbered`: keys of one stem and a number, as pairs (``{Viewport2 cam}``).
* :func:`pairs`: every segment a name and a number (MULTIDRIVE).
* :func:`rest`: the segments no field took, in order (SET's item-specific keys, CONTROL).

The wire order is the field order.  :func:`command` compiles a class's layout once; its
``parse`` and ``format`` are what the dispatch tables hold.  A command
whose rules go beyond this (a bare number standing for SET's Params, REPORT's checks) adds a
``finish`` step, which gets the values read and may check or complete them.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.errors import ProtocolError

from ..grammar import RawMessage, Segment
from .common import (
    _bool,
    _choice,
    _float,
    _int,
    _Line,
    _non_negative_int,
    _positive_float,
    _Reader,
    _text,
    _vec2or3,
    _vec3,
    _word,
)

WIRE = "usarsim.wire"  # the metadata key of a declared field


@dataclass(frozen=True, slots=True)
class Kind:
    """A kind of value: how it is read from a segment (an error says what the key allows) and
    how it is written to a line (:class:`~usarsim.protocol.commands.common._Line`'s method)."""

    read: _Reader
    write: Callable[[_Line, str, Any], object]


TEXT = Kind(_text, _Line.text)
NUMBER = Kind(_float, _Line.number)
POSITIVE = Kind(_positive_float, _Line.number)
INTEGER = Kind(_int, _Line.integer)
COUNT = Kind(_non_negative_int, _Line.integer)
BOOL = Kind(_bool, _Line.boolean)
VEC3 = Kind(_vec3, _Line.vector)
VEC2OR3 = Kind(_vec2or3, _Line.vector)


def choice(kind: Kind, allowed: frozenset[int], text: str) -> Kind:
    """``kind`` narrowed to ``allowed`` (``text`` says what is allowed when a value is not)."""
    return Kind(_choice(kind.read, allowed, text), kind.write)


@dataclass(frozen=True, slots=True)
class Key:
    """One ``{Key value}`` segment: its spelling on the wire, its kind, the other spellings
    accepted, the placeholder the error texts show (``{Link n}``), and whether it may come
    outside its group."""

    wire: str
    kind: Kind
    aliases: tuple[str, ...] = ()
    hint: str = "x"
    outside: str = "refuse"


@dataclass(frozen=True, slots=True)
class Group:
    """Repeated groups of keys (see the module's text); ``noun`` names one in errors."""

    cls: type
    noun: str


@dataclass(frozen=True, slots=True)
class Numbered:
    """``{StemN value}`` keys as ``(N, value)`` pairs."""

    stem: str
    pattern: re.Pattern[str]


@dataclass(frozen=True, slots=True)
class Pairs:
    """Every segment a name and a number; ``what`` names the pair in errors."""

    what: str
    word: str


@dataclass(frozen=True, slots=True)
class Rest:
    """The segments no other field took."""


def key(wire: str, kind: Kind, *aliases: str, default: Any = None, hint: str = "x", outside: str = "refuse") -> Any:
    """A field sent as ``{wire value}`` (see the module's text)."""
    return dataclasses.field(default=default, metadata={WIRE: Key(wire, kind, aliases, hint, outside)})


def group(cls: type, noun: str) -> Any:
    """A field of repeated groups, each a ``cls`` (a dataclass of :func:`key` fields whose first opens it)."""
    return dataclasses.field(default=(), metadata={WIRE: Group(cls, noun)})


def numbered(stem: str) -> Any:
    """A field of ``{StemN value}`` keys, as ``(N, value)`` pairs in the order sent."""
    pattern = re.compile(re.escape(stem) + r"([0-9]{1,3})\Z", re.IGNORECASE)
    return dataclasses.field(default=(), metadata={WIRE: Numbered(stem, pattern)})


def pairs(what: str, word: str) -> Any:
    """A field of ``{name number}`` segments, every one the line has (``what``: the pair as
    the error text shows it, ``word``: what a name is)."""
    return dataclasses.field(default=(), metadata={WIRE: Pairs(what, word)})


def rest() -> Any:
    """A field of the segments no other field took, in order."""
    return dataclasses.field(default=(), metadata={WIRE: Rest()})


class _GroupLayout:
    """A group's keys: the one that opens it first."""

    __slots__ = ("cls", "noun", "fields", "start", "by_wire", "required", "grammar")

    def __init__(self, spec: Group):
        self.cls = spec.cls
        self.noun = spec.noun
        self.fields: list[tuple[str, Key]] = [
            (f.name, f.metadata[WIRE]) for f in dataclasses.fields(spec.cls) if WIRE in f.metadata
        ]
        self.start = self.fields[0]
        self.by_wire = {w.lower(): (name, k) for name, k in self.fields[1:] for w in (k.wire, *k.aliases)}
        self.required = [
            (name, k)
            for f, (name, k) in zip(dataclasses.fields(spec.cls), self.fields, strict=True)
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        ]
        parts = []
        for f in dataclasses.fields(spec.cls):
            k = f.metadata[WIRE]
            text = "{%s %s}" % (k.wire, k.hint)
            optional = f.default is not dataclasses.MISSING and f.name != self.start[0]
            parts.append("[%s]" % text if optional else text)
        self.grammar = " ".join(parts)

    def close(self, cmd: str, values: dict[str, Any]) -> Any:
        for name, k in self.required:
            if name not in values:
                start_name, start = self.start
                raise ProtocolError(
                    f"{cmd}: {{{start.wire} {values[start_name]}}} has no {{{k.wire} {k.hint}}}: "
                    f"each {self.noun} group is {self.grammar}"
                )
        return self.cls(**values)

    def write(self, line: _Line, item: Any) -> None:
        for name, k in self.fields:
            k.kind.write(line, k.wire, getattr(item, name))


class Layout:
    """A command's declared fields, compiled once: its parser and its format."""

    def __init__(self, cls: type, finish: Callable[[str, dict[str, Any], list[Segment]], None] | None = None):
        self.cls = cls
        self.keyword: str = getattr(cls, "keyword")  # noqa: B009  (every command class declares its word)
        self.finish = finish
        self.fields: list[tuple[str, Any]] = [
            (f.name, f.metadata[WIRE]) for f in dataclasses.fields(cls) if WIRE in f.metadata
        ]
        self.keys: dict[str, tuple[str, Kind]] = {}
        self.groups: dict[str, _GroupLayout] = {}  # by field name
        self.numbered: list[tuple[str, Numbered]] = []
        self.pairs: tuple[str, Pairs] | None = None
        self.rest: str | None = None
        for name, spec in self.fields:
            if isinstance(spec, Key):
                for w in (spec.wire, *spec.aliases):
                    self.keys[w.lower()] = (name, spec.kind)
            elif isinstance(spec, Group):
                self.groups[name] = _GroupLayout(spec)
            elif isinstance(spec, Numbered):
                self.numbered.append((name, spec))
            elif isinstance(spec, Pairs):
                self.pairs = (name, spec)
            elif isinstance(spec, Rest):
                self.rest = name
        self.opens = {g.start[1].wire.lower(): name for name, g in self.groups.items()}
        self.members = {w: (name, g) for name, g in self.groups.items() for w in g.by_wire}
        # a command of keys only is read as a table: the first of each key wins
        self.plain = not (self.groups or self.numbered or self.rest is not None)
        self.format = self._compile_format()

    # ---- parsing
    def parse(self, raw: RawMessage) -> Any:
        cmd = raw.type
        if self.pairs is not None:
            return self._parse_pairs(raw)
        values: dict[str, Any] = {}
        if self.plain:
            keys = self.keys
            for seg in raw.segments:
                entry = keys.get(seg.key.lower())
                if entry is not None and entry[0] not in values:
                    values[entry[0]] = entry[1].read(cmd, seg)
            if self.finish is not None:
                self.finish(cmd, values, [])
            return self.cls(**values)
        found: dict[str, list[Any]] = {name: [] for name in self.groups}
        found.update({name: [] for name, _ in self.numbered})
        current: dict[str, dict[str, Any] | None] = {name: None for name in self.groups}
        rest: list[Segment] = []
        for seg in raw.segments:
            low = seg.key.lower()
            opened = self.opens.get(low)
            if opened is not None:
                g = self.groups[opened]
                if current[opened] is not None:
                    found[opened].append(g.close(cmd, current[opened]))  # type: ignore[arg-type]
                current[opened] = {g.start[0]: g.start[1].kind.read(cmd, seg)}
                continue
            member = self.members.get(low)
            if member is not None:
                gname, g = member
                field_name, k = g.by_wire[low]
                open_group = current[gname]
                if open_group is not None:
                    open_group[field_name] = k.kind.read(cmd, seg)
                    continue
                if k.outside == "refuse":
                    start = g.start[1]
                    raise ProtocolError(
                        f"{cmd}: {{{seg.key} {seg.value}}} comes before any {{{start.wire} {start.hint}}}: "
                        f"each {g.noun} group must start with {start.wire}"
                    )
            entry = self.keys.get(low)
            if entry is not None and entry[0] not in values:
                values[entry[0]] = entry[1].read(cmd, seg)
                continue
            for name, spec in self.numbered:
                m = spec.pattern.match(seg.key)
                if m is not None:
                    found[name].append((int(m.group(1)), seg.value))
                    break
            else:
                if self.rest is not None:
                    rest.append(seg)
        for name, g in self.groups.items():
            if current[name] is not None:
                found[name].append(g.close(cmd, current[name]))  # type: ignore[arg-type]
        if self.finish is not None:
            self.finish(cmd, values, rest)
        for name, items in found.items():
            values[name] = tuple(items)
        if self.rest is not None:
            values[self.rest] = tuple(rest)
        return self.cls(**values)

    def _parse_pairs(self, raw: RawMessage) -> Any:
        assert self.pairs is not None
        name, spec = self.pairs
        cmd = raw.type
        items = []
        for seg in raw.segments:
            if not seg.value:
                raise ProtocolError(f"{cmd}: segment {{{seg.key}}} has no value: expected {spec.what}")
            items.append((seg.key, _float(cmd, seg)))
        return self.cls(**{name: tuple(items)})

    # ---- formatting
    def _compile_format(self) -> Callable[[Any], str]:
        """The format as one function written for this command (as dataclasses writes its
        methods): each field in the wire order, a key only when it was set."""
        env: dict[str, Any] = {"_Line": _Line, "_word": _word}
        body = ["def format(c):", f"    line = _Line({self.keyword!r})"]
        for i, (name, spec) in enumerate(self.fields):
            if isinstance(spec, Key):
                env[f"w{i}"] = spec.kind.write
                body += [f"    v = c.{name}", "    if v is not None:", f"        w{i}(line, {spec.wire!r}, v)"]
            elif isinstance(spec, Group):
                env[f"g{i}"] = self.groups[name]
                body += [f"    for item in c.{name}:", f"        g{i}.write(line, item)"]
            elif isinstance(spec, Numbered):
                body += [f"    for index, text in c.{name}:", f"        line.text({spec.stem!r} + str(index), text)"]
            elif isinstance(spec, Pairs):
                body += [
                    f"    for pair, number in c.{name}:",
                    f"        line.number(_word(pair, {spec.word!r}), number)",
                ]
            else:
                body.append(f"    line.segments(c.{name})")
        body.append("    return line.end()")
        exec("\n".join(body), env)  # noqa: S102  (the text above, from the declarations only)
        fn: Callable[[Any], str] = env["format"]
        return fn


def command(cls: type, finish: Callable[[str, dict[str, Any], list[Segment]], None] | None = None) -> Layout:
    """The compiled layout of a declared command class."""
    return Layout(cls, finish)
