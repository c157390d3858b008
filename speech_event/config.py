"""The node's configuration: the seed's Table 1 keys plus the timing keys, read from a plain file.

A line is ``key value`` (tabs or spaces, as in the robot's files) or ``key = value``; ``#`` starts a
comment. Every key may also be spelled in camelCase (``sampleRate``), as the robot's later release
does. A bad file gets one ``ConfigError`` that names the file, line, key, bad value and what is
allowed, before the node starts.
"""

import dataclasses
import difflib
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Dict, Mapping, NamedTuple, Optional, Union


@dataclass(frozen=True)
class SpeechEventConfig:
    language: str = "english"
    verbose_mode: bool = False
    rw_model_path: str = ""
    en_model_path: str = ""
    # Empty: utterances are not stored. Otherwise each utterance is written there as a WAV file.
    audio_storage_dir: str = ""
    cuda: bool = False
    sample_rate: int = 48000
    speech_pause_period: float = 1.5
    max_utterance_length: float = 10.0
    health_check_period: float = 5.0
    publish_unrecognized: bool = False
    # One message longer than this is rejected whole: no microphone block is anywhere near it.
    max_message_length: float = 60.0
    # Transcripts whose engine-reported confidence is below this count as not recognized.
    confidence: float = 0.0
    # Period of the "still running" info line in verbose mode; 0 turns it off.
    heartbeat_msg_period: float = 10.0


class ConfigError(Exception):
    """A configuration that cannot be used; the message says where and what is allowed."""


class _KeyRule(NamedTuple):
    parse: Callable[[object], object]
    allowed: str


def _text(value: object) -> str:
    if not isinstance(value, str):
        raise ValueError("is not text")
    return value


def _boolean(value: object) -> bool:
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.lower() in ("true", "false"):
        return value.lower() == "true"
    raise ValueError("is not a boolean")


def _choice(*options: str) -> Callable[[object], object]:
    def parse(value: object) -> str:
        if isinstance(value, str) and value.lower() in options:
            return value.lower()
        raise ValueError("is not one of the choices")

    return parse


_NUMBER_PATTERNS = {int: r"[-+]?\d+", float: r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?"}


def _number(kind: type, low: float, high: float) -> Callable[[object], object]:
    def parse(value: object) -> Union[int, float]:
        not_a_number = ValueError("is not " + ("an integer" if kind is int else "a number"))
        if isinstance(value, str):
            if not re.fullmatch(_NUMBER_PATTERNS[kind], value):
                raise not_a_number  # float() would also take 'nan' and 'inf'
            number: Union[int, float] = kind(value)
        elif (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or (kind is int and isinstance(value, float))
        ):
            raise not_a_number
        else:
            number = kind(value)
        if not low <= number <= high:
            raise ValueError("is out of range")
        return number

    return parse


def _seconds(low: float, high: float) -> _KeyRule:
    return _KeyRule(_number(float, low, high), f"a number of seconds from {low} to {high}")


_RULES: Dict[str, _KeyRule] = {
    "language": _KeyRule(_choice("kinyarwanda", "english"), "kinyarwanda or english"),
    "verbose_mode": _KeyRule(_boolean, "true or false"),
    "rw_model_path": _KeyRule(_text, "a path"),
    "en_model_path": _KeyRule(_text, "a path"),
    "audio_storage_dir": _KeyRule(_text, "a directory path, or nothing to store no audio"),
    "cuda": _KeyRule(_boolean, "true or false"),
    "sample_rate": _KeyRule(_number(int, 8000, 192000), "an integer number of Hz from 8000 to 192000"),
    "speech_pause_period": _seconds(0.05, 60.0),
    "max_utterance_length": _seconds(1.0, 300.0),
    "health_check_period": _seconds(0.1, 3600.0),
    "publish_unrecognized": _KeyRule(_boolean, "true or false"),
    "max_message_length": _seconds(0.1, 3600.0),
    "confidence": _KeyRule(_number(float, 0.0, 1.0), "a number from 0 to 1"),
    "heartbeat_msg_period": _seconds(0.0, 3600.0),
}
assert set(_RULES) == {f.name for f in dataclasses.fields(SpeechEventConfig)}


def _camel_case(key: str) -> str:
    return re.sub(r"_([a-z])", lambda match: match.group(1).upper(), key)


# Every spelling a file may use, mapped to the field it sets.
_SPELLINGS: Dict[str, str] = {}
for _key in _RULES:
    _SPELLINGS[_key] = _key
    _SPELLINGS[_camel_case(_key)] = _key

# A key alone sets it to the empty value: how a file says "no path".
_LINE = re.compile(r"^(?P<key>[A-Za-z_][A-Za-z0-9_]*)(?:(?:\s*=\s*|\s+)(?P<value>.*))?$")


def _unknown_key_message(key: str) -> str:
    close = difflib.get_close_matches(key, list(_SPELLINGS), n=1, cutoff=0.6)
    hint = f"did you mean '{close[0]}'? " if close else ""
    return "unknown key '{}': {}known keys are {}".format(key, hint, ", ".join(_RULES))


def _where(source: str, line: Optional[int]) -> str:
    return f"{source}:{line}" if line is not None else source


def _parse_value(key: str, raw: object, where: str) -> object:
    rule = _RULES[key]
    try:
        return rule.parse(raw)
    except ValueError as problem:
        raise ConfigError(f"{where}: key '{key}': value {raw!r} {problem}; allowed: {rule.allowed}") from None


def apply_overrides(
    base: SpeechEventConfig, overrides: Mapping[str, object], source: str
) -> SpeechEventConfig:
    """``base`` with ``overrides`` (already typed, as from TOML) checked and applied."""
    values: Dict[str, object] = {}
    for spelling, raw in overrides.items():
        if spelling not in _SPELLINGS:
            raise ConfigError(f"{source}: {_unknown_key_message(spelling)}")
        values[_SPELLINGS[spelling]] = _parse_value(_SPELLINGS[spelling], raw, source)
    return dataclasses.replace(base, **values)  # type: ignore[arg-type]


def parse_config(text: str, source: str = "<config>") -> SpeechEventConfig:
    """Parse the text of a configuration file; keys it does not set keep their defaults."""
    values: Dict[str, object] = {}
    first_line: Dict[str, int] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        # A '#' starts a comment at the line start or after white space, so paths may hold '#'.
        content = re.split(r"(?:^|\s)#", line, maxsplit=1)[0].strip()
        if not content:
            continue
        match = _LINE.match(content)
        where = _where(source, number)
        if match is None:
            raise ConfigError(f"{where}: cannot read {content!r}; expected 'key value' or 'key = value'")
        spelling, raw = match.group("key"), (match.group("value") or "").strip()
        if spelling not in _SPELLINGS:
            raise ConfigError(f"{where}: {_unknown_key_message(spelling)}")
        key = _SPELLINGS[spelling]
        if key in first_line:
            raise ConfigError(
                f"{where}: key '{key}' is set again (first set on line {first_line[key]}); set each key once"
            )
        first_line[key] = number
        values[key] = _parse_value(key, raw, where)
    return dataclasses.replace(SpeechEventConfig(), **values)  # type: ignore[arg-type]


def format_config(config: SpeechEventConfig) -> str:
    """The text of a configuration file that ``parse_config`` reads back as ``config``."""

    def text(value: object) -> str:
        return str(value).lower() if isinstance(value, bool) else str(value)

    return "".join(
        f"{field.name} {text(getattr(config, field.name))}\n" for field in dataclasses.fields(config)
    )


def load_config(path: Union[str, Path]) -> SpeechEventConfig:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as problem:
        raise ConfigError(f"{path}: cannot read the configuration file: {problem.strerror}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: the configuration file is not UTF-8 text") from None
    return parse_config(text, str(path))
