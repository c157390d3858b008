"""Plain ``key value`` configuration files, read into a frozen dataclass.

A line is ``key value`` (tabs or spaces, as in the robot's files) or ``key = value``; ``#`` starts a
comment at the line start or after white space (so paths may hold '#'); a key alone sets the empty
value. Every key may also be spelled in camelCase (``sampleRate``), as the robot's later release
does. A bad file gets one ``ConfigError`` naming the file, line, key, bad value and what is allowed.
"""

import dataclasses
import difflib
import re
from pathlib import Path
from typing import Any, Callable, Dict, Generic, Mapping, NamedTuple, Optional, Tuple, Type, TypeVar, Union

from speech_event.errors import ConfigError

# No configuration is anywhere near this; reading more would only fill memory (/dev/zero).
MAX_FILE_BYTES = 2**20


class KeyRule(NamedTuple):
    """How one key's value is read (``parse`` raises ValueError), and what is allowed (for the error)."""

    parse: Callable[[object], object]
    allowed: str
    # The value names a file: a scenario takes a relative one from its own folder.
    path: bool = False


def text(value: object) -> str:
    """A text value as it is; ValueError for anything else."""
    if not isinstance(value, str):
        raise ValueError("is not text")
    return value


def boolean(value: object) -> bool:
    """``true`` or ``false`` in any case (or a bool) as a bool."""
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.lower() in ("true", "false"):
        return value.lower() == "true"
    raise ValueError("is not a boolean")


def choice(*options: str) -> Callable[[object], object]:
    """A parser of one of ``options``, in any case; it gives the option in lower case."""

    def parse(value: object) -> str:
        if isinstance(value, str) and value.lower() in options:
            return value.lower()
        raise ValueError("is not one of the choices")

    return parse


_NUMBER_PATTERNS = {int: r"[-+]?\d+", float: r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?"}


def optional(parse: Callable[[object], object]) -> Callable[[object], object]:
    """``parse``, or None for an empty value (the key's default is then decided elsewhere)."""

    def parse_or_none(value: object) -> object:
        return None if value is None or value == "" else parse(value)

    return parse_or_none


def number(kind: type, low: float, high: float) -> Callable[[object], object]:
    """A parser of a ``kind`` (int or float) number from ``low`` to ``high``; no nan, inf or bool."""

    def parse(value: object) -> Union[int, float]:
        not_a_number = ValueError("is not " + ("an integer" if kind is int else "a number"))
        if isinstance(value, str):
            if not re.fullmatch(_NUMBER_PATTERNS[kind], value):
                raise not_a_number  # float() would also take 'nan' and 'inf'
            parsed: Union[int, float] = kind(value)
        elif (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or (kind is int and isinstance(value, float))
        ):
            raise not_a_number
        else:
            parsed = kind(value)
        if not low <= parsed <= high:
            raise ValueError("is out of range")
        return parsed

    return parse


def seconds(low: float, high: float) -> KeyRule:
    """The rule of a key in seconds, from ``low`` to ``high``."""
    return KeyRule(number(float, low, high), f"a number of seconds from {low} to {high}")


def file_path(allowed: str) -> KeyRule:
    """The rule of a key whose value is a file's path, as text."""
    return KeyRule(text, allowed, path=True)


def _camel_case(key: str) -> str:
    return re.sub(r"_([a-z])", lambda match: match.group(1).upper(), key)


# A key alone sets it to the empty value: how a file says "no path".
_LINE = re.compile(r"^(?P<key>[A-Za-z_][A-Za-z0-9_]*)(?:(?:\s*=\s*|\s+)(?P<value>.*))?$")

Config = TypeVar("Config")


class KeyValueFormat(Generic[Config]):
    """How the keys of one dataclass are written in a file, and checked."""

    def __init__(
        self,
        config_type: Type[Config],
        rules: Dict[str, KeyRule],
        aliases: Optional[Mapping[str, str]] = None,
        check: Optional[Callable[[Config], Optional[str]]] = None,
    ) -> None:
        """``check`` says what is wrong with values that are each allowed but not together."""
        fields = {field.name for field in dataclasses.fields(config_type)}  # type: ignore[arg-type]
        assert set(rules) == fields, "every field needs a rule, and every rule a field"
        self._type = config_type
        self._rules = rules
        self._check = check
        # Every spelling a file may use, mapped to the field it sets.
        self._spellings: Dict[str, str] = {}
        for key in rules:
            self._spellings[key] = key
            self._spellings[_camel_case(key)] = key
        for alias, key in (aliases or {}).items():
            assert key in rules, f"alias {alias} of unknown key {key}"
            self._spellings[alias] = key

    @property
    def path_keys(self) -> Tuple[str, ...]:
        """The keys whose values name files."""
        return tuple(key for key, rule in self._rules.items() if rule.path)

    def names_a_file(self, spelling: str) -> bool:
        """Whether ``spelling`` (a key, its camelCase or an alias) sets a key that names a file."""
        key = self._spellings.get(spelling)
        return key is not None and self._rules[key].path

    def _unknown_key(self, where: str, key: str) -> ConfigError:
        close = difflib.get_close_matches(key, list(self._spellings), n=1, cutoff=0.6)
        hint = f"did you mean '{close[0]}'? " if close else ""
        return ConfigError(f"{where}: unknown key '{key}': {hint}known keys are {', '.join(self._rules)}")

    def _value(self, key: str, raw: object, where: str) -> object:
        rule = self._rules[key]
        try:
            return rule.parse(raw)
        except ValueError as problem:
            raise ConfigError(
                f"{where}: key '{key}': value {raw!r} {problem}; allowed: {rule.allowed}"
            ) from None

    def apply_overrides(self, base: Config, overrides: Mapping[str, object], source: str) -> Config:
        """``base`` with ``overrides`` (already typed, as from TOML) checked and applied."""
        values: Dict[str, Any] = {}
        for spelling, raw in overrides.items():
            if spelling not in self._spellings:
                raise self._unknown_key(source, spelling)
            values[self._spellings[spelling]] = self._value(self._spellings[spelling], raw, source)
        return self._checked(dataclasses.replace(base, **values), source)  # type: ignore[type-var]

    def parse(self, content: str, source: str) -> Config:
        """Parse the text of a file; keys it does not set keep their defaults."""
        values: Dict[str, Any] = {}
        first_line: Dict[str, int] = {}
        for line_number, line in enumerate(content.splitlines(), start=1):
            setting = re.split(r"(?:^|\s)#", line, maxsplit=1)[0].strip()
            if not setting:
                continue
            where = f"{source}:{line_number}"
            match = _LINE.match(setting)
            if match is None:
                raise ConfigError(f"{where}: cannot read {setting!r}; expected 'key value' or 'key = value'")
            spelling, raw = match.group("key"), (match.group("value") or "").strip()
            if spelling not in self._spellings:
                raise self._unknown_key(where, spelling)
            key = self._spellings[spelling]
            if key in first_line:
                first = first_line[key]
                raise ConfigError(
                    f"{where}: key '{key}' is set again (first set on line {first}); set each key once"
                )
            first_line[key] = line_number
            values[key] = self._value(key, raw, where)
        return self._checked(self._type(**values), source)

    def _checked(self, config: Config, source: str) -> Config:
        problem = self._check(config) if self._check is not None else None
        if problem:
            raise ConfigError(f"{source}: {problem}")
        return config

    def load(self, path: Union[str, Path]) -> Config:
        try:
            with open(path, "rb") as file:  # read at most one byte past the limit: /dev/zero ends
                raw = file.read(MAX_FILE_BYTES + 1)
        except OSError as problem:
            raise ConfigError(f"{path}: cannot read the configuration file: {problem.strerror}") from None
        if len(raw) > MAX_FILE_BYTES:
            raise ConfigError(
                f"{path}: the configuration file is over {MAX_FILE_BYTES // 2**20} MB; a configuration is "
                "a few lines of 'key value'"
            )
        try:
            content = raw.decode("utf-8-sig")  # a byte-order mark (Windows editors) is fine
        except UnicodeDecodeError:
            raise ConfigError(f"{path}: the configuration file is not UTF-8 text") from None
        return self.parse(content, str(path))

    def format(self, config: Config) -> str:
        """The text of a file that ``parse`` reads back as ``config``."""

        def written(value: object) -> str:
            if value is None:
                return ""  # an optional key left empty: its default, as ``optional`` reads it
            return str(value).lower() if isinstance(value, bool) else str(value)

        return "".join(f"{key} {written(getattr(config, key))}\n" for key in self._rules)
