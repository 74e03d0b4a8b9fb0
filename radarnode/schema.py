"""Frozen dataclasses from YAML: the one loader the scenario and the radar options share.

A :class:`Source` keeps the parsed document and the line of every node; :func:`build` turns a mapping into a
validated dataclass, following a :class:`Schema` (which fields hold nested dataclasses, YAML aliases, fields
the file never sets). Unknown keys and missing required fields are found from the dataclass definitions, and
a :class:`FieldError` raised by a dataclass becomes a :class:`ScenarioError` naming the file, the line, the
dotted field path, the value and what is allowed.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field

import yaml

from radarnode.errors import FieldError, ScenarioError, yaml_repr


class Loader(yaml.SafeLoader):
    """PyYAML's safe loader reading plain scalars by YAML 1.2's core schema (JSON's numbers, booleans and null)
    instead of the YAML 1.1 PyYAML implements.

    Numbers: ``1e-5``, ``2E6`` and ``1.0e5`` are floats (YAML 1.1 wanted a dot and a signed exponent, and read
    them as text, which a scenario field then refused); ``0o17`` and ``0x1F`` are integers and ``012`` is twelve
    (1.1: octal). What 1.2 does not have is text: ``1:30`` (1.1 read base 60: 90), ``1_000`` (1.1 dropped the
    underscore), dates. Booleans are ``true`` and ``false`` (in three spellings); ``yes``, ``no``, ``on`` and
    ``off`` are text. A field then refuses the text and says why (:func:`quoted_number_hint`). Quoted text stays
    text.
    """

    yaml_implicit_resolvers: dict = {}


for _tag, _pattern, _first in (
        ("tag:yaml.org,2002:null", r"^(?:~|null|Null|NULL|)$", ["~", "n", "N", ""]),
        ("tag:yaml.org,2002:bool", r"^(?:true|True|TRUE|false|False|FALSE)$", list("tTfF")),
        ("tag:yaml.org,2002:int", r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$", list("-+0123456789")),
        ("tag:yaml.org,2002:float",
         r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$",
         list("-+0123456789.")),
        ("tag:yaml.org,2002:merge", r"^(?:<<)$", ["<"])):
    Loader.add_implicit_resolver(_tag, re.compile(_pattern), _first)


def _construct_int(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> int:
    text = loader.construct_scalar(node)
    if text.startswith(("0o", "0x")):
        return int(text[2:], 8 if text[1] == "o" else 16)
    return int(text, 10)


def _construct_float(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
    text = loader.construct_scalar(node).lower()
    if text.endswith(".inf"):
        return -math.inf if text.startswith("-") else math.inf
    return math.nan if text == ".nan" else float(text)


def _construct_bool(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> bool:
    return loader.construct_scalar(node).lower() == "true"


Loader.add_constructor("tag:yaml.org,2002:int", _construct_int)
Loader.add_constructor("tag:yaml.org,2002:float", _construct_float)
Loader.add_constructor("tag:yaml.org,2002:bool", _construct_bool)


@dataclass(frozen=True)
class Schema:
    """How YAML maps onto a family of dataclasses."""

    #: class -> {field: (nested class, is a list)}
    nested: dict = field(default_factory=dict)
    #: class -> {YAML key: dataclass field} where they differ
    aliases: dict = field(default_factory=dict)
    #: fields the loader fills itself, never read from the file
    internal: frozenset = frozenset({"source", "lines"})
    #: class -> {list field: what is expected instead of an empty list}: lists that, written, must hold something
    non_empty: dict = field(default_factory=dict)


#: a scenario's values nest a few levels deep (actors → waypoints → a waypoint's fields): deeper is a mistake
MAX_DEPTH = 64
#: values in one scenario file once its aliases are expanded, at most (the largest shipped scenario holds a few
#: hundred)
MAX_VALUES = 100_000


def _short(path: str, most: int = 60) -> str:
    """A dotted field path for a message, cut to its first ``most`` characters."""
    return path if len(path) <= most else path[:most] + "…"


class Source:
    """A parsed YAML document with the line of every node, keyed by its dotted path."""

    def __init__(self, path: str, text: str) -> None:
        self.path = path
        self.lines: dict[str, int] = {}
        self._values = 0
        self._count_events(path, text)
        try:
            node = yaml.compose(text, Loader=Loader)
        except RecursionError:                           # thousands of nested brackets
            raise ScenarioError(f"{path}: not valid YAML here: nested deeper than the YAML parser can follow; expected "
                                f"a scenario's few levels (at most {MAX_DEPTH})") from None
        except yaml.reader.ReaderError as exc:          # a character YAML does not allow (a control character)
            line = text[:exc.position].count("\n") + 1
            char = exc.character if isinstance(exc.character, int) else ord(exc.character)
            kind = "a control character" if char < 0x20 or 0x7F <= char <= 0x9F else "not printable"
            raise ScenarioError(f"{path}:{line}: not valid YAML: character U+{char:04X} is not allowed in a YAML "
                                f"file ({kind}); expected printable text") from None
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            where = f":{mark.line + 1}" if mark is not None else ""
            problem = " ".join(str(getattr(exc, "problem", None) or exc).split())      # one line
            raise ScenarioError(f"{path}{where}: not valid YAML: {problem}") from None
        if node is None:
            raise ScenarioError(f"{path}: the file is empty; expected a mapping with name, duration_s and seed")
        self.data = self._convert(node, "")

    @staticmethod
    def _count_events(path: str, text: str) -> None:
        """Refuse a file of more than MAX_VALUES values before the (pure-Python) composer builds its nodes: a 16-MB
        list took minutes and gigabytes to be refused after it (an independent tester's finding). The C parser where
        PyYAML has it; a file it cannot parse is left to the composer, which says where."""
        events = 0
        try:
            for _ in yaml.parse(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
                events += 1
                if events > 2 * MAX_VALUES + 16:        # (a value is one event, a mapping's key another)
                    raise ScenarioError(f"{path}: more than {MAX_VALUES} values; expected a scenario of at most that "
                                        "many")
        except (yaml.YAMLError, RecursionError):
            return

    @classmethod
    def of_lines(cls, path: str, lines: dict[str, int]) -> Source:
        """A source already parsed: its name and the line of each dotted path (to name lines in later errors)."""
        src = cls.__new__(cls)
        src.path, src.lines, src.data = path, dict(lines), None
        return src

    def _convert(self, node: yaml.Node, path: str, depth: int = 0) -> object:
        self.lines[path] = node.start_mark.line + 1
        self._values += 1
        if depth > MAX_DEPTH:
            # (a recursive alias, ``a: &a [*a]``, nests without end: a RecursionError traceback before)
            raise ScenarioError(f"{self.path}:{node.start_mark.line + 1}: field '{_short(path)}' is nested deeper than "
                                f"{MAX_DEPTH} levels (a recursive alias?); expected a scenario's few levels")
        if self._values > MAX_VALUES:
            # (aliases of aliases expand exponentially: such a file ran for minutes before)
            raise ScenarioError(f"{self.path}:{node.start_mark.line + 1}: more than {MAX_VALUES} values once its "
                                f"aliases are expanded (at field '{_short(path)}'); expected a scenario of at most that many")
        if isinstance(node, yaml.MappingNode):
            out = {}
            for key_node, value_node in node.value:
                if not isinstance(key_node, yaml.ScalarNode):
                    # (a list or mapping as a key, ``{[a, b]: 1}``: a TypeError traceback before, a tester's finding)
                    what = "a list" if isinstance(key_node, yaml.SequenceNode) else "a mapping"
                    raise ScenarioError(f"{self.path}:{key_node.start_mark.line + 1}: a key of "
                                        f"{'field ' + repr(_short(path)) if path else 'the top level'} is {what}; "
                                        "expected a field name")
                key = key_node.value
                child = f"{path}.{key}" if path else str(key)
                if key in out:
                    raise ScenarioError(f"{self.path}:{key_node.start_mark.line + 1}: field '{child}' appears twice")
                self.lines[child] = key_node.start_mark.line + 1
                out[key] = self._convert(value_node, child, depth + 1)
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self._convert(v, f"{path}[{i}]", depth + 1) for i, v in enumerate(node.value)]
        loader = Loader("")
        return loader.construct_object(node, deep=True)

    def error(self, path: str, message: str) -> ScenarioError:
        return ScenarioError(f"{self.where(path)}: {message}")

    def where(self, path: str) -> str:
        """``file:line`` of the dotted field path (or of the nearest enclosing field that has a line), else ``file``."""
        line = self._line(path)
        return f"{self.path}:{line}" if line else self.path

    def _line(self, path: str) -> int | None:
        while True:
            if path in self.lines:       # ("": the top level's, or an empty top-level key's)
                return self.lines[path]
            if not path:
                return None
            path = path.rsplit(".", 1)[0] if "." in path else path.split("[")[0] if "[" in path else ""


#: a field name as an error shows it in quotes: no line break, quote or space
_PLAIN_NAME = re.compile(r"[^\s'\"]+")


def quoted_number_hint(value: object) -> str:
    """A hint for a number written as text: ``"25"`` in quotes (the field wants the number itself), or a form only
    YAML 1.1 read as a number (``1:30`` in base 60, ``1_000``), which YAML 1.2 reads as text."""
    if isinstance(value, str):
        if re.fullmatch(r"[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?", value):
            sign, digits = (-1.0, value[1:]) if value.startswith("-") else (1.0, value.lstrip("+"))
            base60 = 0.0
            for part in digits.replace("_", "").split(":"):
                base60 = 60.0 * base60 + float(part)
            return (f" (this is text: YAML 1.2 has no base-60 numbers, where YAML 1.1 read {sign * base60:g}; write "
                    "the number itself)")
        try:
            number = float(value.replace("_", ""))
        except ValueError:
            return ""
        if "_" in value and math.isfinite(number):
            return " (this is text: YAML 1.2 numbers have no '_' separators; write the digits alone)"
        if math.isfinite(number):
            return " (this is text: write the number without quotes)"
    return ""


def build(cls: type, data: object, path: str, src: Source, schema: Schema, extra: dict | None = None,
          who: str = ""):
    """Build dataclass ``cls`` from the parsed mapping ``data`` found at dotted ``path``; errors name file and line,
    and the list item they are in by its ``id`` where it has one (``who``: "actor 'lead'")."""
    where = path or "top level"
    if path.endswith("]") and isinstance(data, dict) and isinstance(data.get("id"), str):
        who = f"{path.rsplit('.', 1)[-1].split('[')[0].removesuffix('s')} {data['id']!r}"
    named = f" ({who})" if who else ""
    if not isinstance(data, dict):
        what = "a mapping" if path else "a mapping of the scenario's fields (name, duration_s, seed, …)"
        raise src.error(path, f"field '{where}': value {yaml_repr(data)} is not allowed; expected {what}")
    aliases = schema.aliases.get(cls, {})
    inverse = {v: k for k, v in aliases.items()}
    fields = {f.name: f for f in dataclasses.fields(cls) if f.name not in schema.internal}
    allowed = sorted(inverse.get(n, n) for n in fields)
    kwargs = dict(extra or {})
    for key, value in data.items():
        name = aliases.get(key, key)
        child = f"{path}.{key}" if path else str(key)
        if name not in fields or not isinstance(key, str):
            # a key that is not a plain name (a block scalar's text with its line break, an empty one; a control or
            # invisible character, which a terminal would act on or hide) escaped, on one line
            shown = f"'{child}'" if isinstance(key, str) and key.isprintable() and _PLAIN_NAME.fullmatch(key) else \
                f"{yaml_repr(key)}" + (f" (in field '{path}')" if path else " (at the top level)")
            raise src.error(child, f"unknown field {shown}; allowed here: {', '.join(allowed)}")
        nested = schema.nested.get(cls, {}).get(name)
        if nested is not None and value is None:
            # a section or list written with nothing after it (``road:``) is YAML's null, not "the defaults"
            what = "a list" if nested[1] else "a mapping of its fields"
            raise src.error(child, f"field '{child}': value null (written as null, ~ or nothing after '{key}:') is not "
                                   f"allowed; expected {what}, or no field '{key}' at all")
        if nested is not None:
            sub, many = nested
            if many:
                if not isinstance(value, list):
                    raise src.error(child, f"field '{child}': value {yaml_repr(value)} is not allowed; expected a "
                                    "list")
                meaning = schema.non_empty.get(cls, {}).get(name)
                if not value and meaning is not None:
                    raise src.error(child, f"field '{child}': value [] is not allowed; expected {meaning}")
                value = tuple(build(sub, v, f"{child}[{i}]", src, schema, who=who) for i, v in enumerate(value))
            else:
                value = build(sub, value, child, src, schema, who=who)
        kwargs[name] = value
    for name, f in fields.items():
        required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        if required and name not in kwargs:
            key = inverse.get(name, name)
            raise src.error(path, f"missing required field '{(path + '.') if path else ''}{key}' in {where}")
    try:
        return cls(**kwargs)
    except FieldError as exc:
        key = inverse.get(exc.field.split(".")[0], exc.field.split(".")[0])
        rest = exc.field[len(exc.field.split(".")[0]):]
        child = (f"{path}.{key}" if path else key) + rest
        raise src.error(child, f"field '{child}'{named}: value {yaml_repr(exc.value)} is not allowed; expected "
                               f"{exc.allowed}{quoted_number_hint(exc.value)}") from None
    except TypeError as exc:  # pragma: no cover - defensive: a field the schema does not describe
        raise src.error(path, f"{where}: {exc}") from None
