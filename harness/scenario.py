"""Scenario files: what soundDetection does over time, and the exact text the node must publish.

The format is a contract shared with scenarios written elsewhere (see README.md). A file that does
not follow it gets a ``ScenarioError`` naming the file, the place in it and what is allowed.
"""

import argparse
import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Tuple, Union

from fixtures.noises import NOISE_KINDS
from harness.catalog import FIXTURE_PREFIX, RECOGNIZERS, VOICES
from speech_event.config import SpeechEventConfig, apply_overrides, load_config, names_a_file
from speech_event.errors import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - the robot's Python
    import tomli as tomllib

MALFORMED_KINDS = ("empty", "nan", "inf", "out_of_range", "multichannel", "oversized", "wrong_type")
OUTAGE_KINDS = ("shutdown", "crash")
# What a client's call may wait for (`after`): "text", the text of the utterance before it, as the
# Behaviour Controller sets its next grammar or disables the node only once the answer has come.
AFTER = ("text",)
DEFAULT_NOISE_DB = -40.0


class ScenarioError(Exception):
    """A scenario file that does not follow the format."""


@dataclass(frozen=True)
class Masking:
    """Noise under a step's speech: ``kind`` (NOISE_KINDS, or a sound file) ``snr_db`` below it."""

    kind: str
    snr_db: float


@dataclass(frozen=True)
class Say:
    text: str
    noise: Optional[Masking] = None


@dataclass(frozen=True)
class Play:
    """A recording (a file next to the scenario, anything soundfile reads), ``gain_db`` louder."""

    path: str
    gain_db: float = 0.0
    noise: Optional[Masking] = None


@dataclass(frozen=True)
class Silence:
    seconds: float


@dataclass(frozen=True)
class Noise:
    seconds: float
    level_db: float = DEFAULT_NOISE_DB
    kind: str = "white"  # NOISE_KINDS, or a sound file next to the scenario


@dataclass(frozen=True)
class Malformed:
    kind: str


@dataclass(frozen=True)
class Outage:
    seconds: float
    kind: str = "shutdown"


@dataclass(frozen=True)
class Enable:
    """A set_enabled call with this exact request string; takes no scenario time."""

    request: str
    after_text: bool = False  # made once the text of the utterance before it has come


@dataclass(frozen=True)
class Language:
    """A set_language call with this exact request string; takes no scenario time."""

    request: str
    after_text: bool = False  # made once the text of the utterance before it has come


@dataclass(frozen=True)
class SetGrammar:
    """A set_grammar call with this request (phrases parted by |, a file next to the scenario, or ""
    for free speech); takes no scenario time."""

    request: str
    after_text: bool = False  # made once the text of the utterance before it has come


@dataclass(frozen=True)
class Listen:
    """A recognise_speech goal with this wait; takes no scenario time (later steps run meanwhile)."""

    wait: float
    after_text: bool = False  # sent once the text of the utterance before it has come


Step = Union[Say, Play, Silence, Noise, Malformed, Outage, Enable, Language, SetGrammar, Listen]


@dataclass(frozen=True)
class ExpectedPartial:
    """A text on /speechEvent/partial and when it comes (checked in memory; on ROS, the order)."""

    at: float
    text: str


# A transcript expectation's keys and their types (msg/Transcript.msg); text and final are required.
TRANSCRIPT_FIELDS: Dict[str, Union[type, Tuple[type, ...]]] = {
    "text": str,
    "final": bool,
    "confidence": (int, float),
    "language": str,
    "engine": str,
    "first_block": (int, float),
    "last_block": (int, float),
}
# Times on the node's clock: checked in memory, where they are the node's own to the instant.
TRANSCRIPT_TIMES = ("first_block", "last_block")


@dataclass(frozen=True)
class Scenario:
    name: str
    source: str
    config: SpeechEventConfig
    steps: Tuple[Step, ...]
    expected: Tuple[str, ...]
    # Every service response, in call order, and every action result in the order the goals end
    # (see harness/report.py for how a result is written); None: not checked.
    expected_responses: Optional[Tuple[int, ...]] = None
    expected_results: Optional[Tuple[str, ...]] = None
    # Every text on /speechEvent/partial, in order, with its scenario time; None: not checked.
    expected_partials: Optional[Tuple[ExpectedPartial, ...]] = None
    # Every /speechEvent/transcript message, in order: the fields given (TRANSCRIPT_FIELDS); None:
    # not checked.
    expected_transcripts: Optional[Tuple[Mapping[str, Any], ...]] = None
    voice: str = "tones"
    recognizer: str = "fake"
    background_noise_db: Optional[float] = None
    # Seeds every random draw (noise), so a scenario gives the same audio on every run.
    seed: int = 0


_TOP_KEYS = (
    "name",
    "voice",
    "recognizer",
    "background_noise_db",
    "seed",
    "config",
    "steps",
    "expect",
)
_STEP_KEYS = {
    "say": ("say", "noise", "snr_db"),
    "play": ("play", "gain_db", "noise", "snr_db"),
    "silence": ("silence",),
    "noise": ("noise", "level_db", "kind"),
    "malformed": ("malformed",),
    "outage": ("outage", "kind"),
    "enable": ("enable", "after"),
    "language": ("language", "after"),
    "grammar": ("grammar", "after"),
    "listen": ("listen", "after"),
}


_REQUIRED = object()


class _Reader:
    """Typed access to one table of the file, with errors that say where."""

    def __init__(self, table: Mapping[str, Any], where: str, allowed: Tuple[str, ...]) -> None:
        unknown = sorted(set(table) - set(allowed))
        if unknown:
            raise ScenarioError(
                "{}: unknown key '{}'; allowed keys: {}".format(where, unknown[0], ", ".join(allowed))
            )
        self._table = table
        self.where = where

    def has(self, key: str) -> bool:
        return key in self._table

    def get(self, key: str, kind: Union[type, Tuple[type, ...]], default: Any = _REQUIRED) -> Any:
        if key not in self._table:
            if default is _REQUIRED:
                raise ScenarioError(f"{self.where}: '{key}' is required")
            return default
        value = self._table[key]
        if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
            names = kind.__name__ if isinstance(kind, type) else " or ".join(k.__name__ for k in kind)
            raise ScenarioError(f"{self.where}: '{key}' = {value!r} must be of type {names}")
        return value

    def seconds(self, key: str, allow_zero: bool = False) -> float:
        value = float(self.get(key, (int, float)))
        if not (value >= 0 if allow_zero else value > 0) or value > 3600:
            lowest = "0 or more" if allow_zero else "above 0"
            raise ScenarioError(
                f"{self.where}: '{key}' = {value} must be a number of seconds {lowest} and at most 3600"
            )
        return value

    def optional_list(self, key: str, kind: type, what: str) -> Optional[Tuple[Any, ...]]:
        values = self.get(key, list, None)
        if values is None:
            return None
        if not all(isinstance(value, kind) and not isinstance(value, bool) for value in values):
            raise ScenarioError(f"{self.where}: '{key}' must be a list of {what}")
        return tuple(values)

    def choice(self, key: str, options: Tuple[str, ...], default: Any = _REQUIRED) -> str:
        value = str(self.get(key, str, default))
        if value not in options:
            raise ScenarioError(
                "{}: '{}' = {!r} is not allowed; allowed: {}".format(
                    self.where, key, value, ", ".join(options)
                )
            )
        return value


def _step(table: Any, where: str) -> Step:
    if not isinstance(table, dict):
        raise ScenarioError(f'{where}: a step must be a table such as {{ say = "hello" }}')
    kinds = [kind for kind in _STEP_KEYS if kind in table]
    if "noise" in kinds and ("say" in kinds or "play" in kinds):
        kinds.remove("noise")  # noise under the speech, not a step of its own
    if len(kinds) != 1:
        raise ScenarioError(
            "{}: a step needs exactly one of {}; it has {}".format(
                where, ", ".join(_STEP_KEYS), ", ".join(sorted(table)) or "none"
            )
        )
    kind = kinds[0]
    reader = _Reader(table, where, _STEP_KEYS[kind])
    if kind == "say":
        return Say(reader.get("say", str), _masking(reader))
    if kind == "play":
        gain_db = float(reader.get("gain_db", (int, float), 0.0))
        return Play(reader.get("play", str), gain_db, _masking(reader))
    if kind == "silence":
        return Silence(reader.seconds("silence"))
    if kind == "noise":
        level_db = float(reader.get("level_db", (int, float), DEFAULT_NOISE_DB))
        return Noise(reader.seconds("noise"), level_db, _noise_kind(reader, "kind", "white"))
    if kind == "malformed":
        return Malformed(reader.choice("malformed", MALFORMED_KINDS))
    after_text = reader.has("after") and reader.choice("after", AFTER) == "text"
    if kind == "enable":
        return Enable(reader.get("enable", str), after_text)
    if kind == "language":
        return Language(reader.get("language", str), after_text)
    if kind == "grammar":
        return SetGrammar(reader.get("grammar", str), after_text)
    if kind == "listen":
        return Listen(reader.seconds("listen", allow_zero=True), after_text)
    return Outage(reader.seconds("outage"), reader.choice("kind", OUTAGE_KINDS, "shutdown"))


def _noise_kind(reader: _Reader, key: str, default: Any = _REQUIRED) -> str:
    """One of NOISE_KINDS, or a sound file's name (found next to the scenario)."""
    kind = str(reader.get(key, str, default))
    if not kind:
        raise ScenarioError(
            "{}: '{}' is empty; allowed: {} or a sound file".format(reader.where, key, ", ".join(NOISE_KINDS))
        )
    return kind


def _masking(reader: _Reader) -> Optional[Masking]:
    """The noise under a say or play step, and its snr_db (each needs the other)."""
    if reader.has("noise") != reader.has("snr_db"):
        raise ScenarioError(f"{reader.where}: 'noise' and 'snr_db' go together: give both or neither")
    if not reader.has("noise"):
        return None
    snr_db = float(reader.get("snr_db", (int, float)))
    if not -40 <= snr_db <= 100:
        raise ScenarioError(f"{reader.where}: 'snr_db' = {snr_db} must be a number of dB from -40 to 100")
    return Masking(_noise_kind(reader, "noise"), snr_db)


def parse_scenario(document: Dict[str, Any], source: str, base_config: SpeechEventConfig) -> Scenario:
    top = _Reader(document, source, _TOP_KEYS)
    overrides = {
        spelling: _from_folder(spelling, value, source)
        for spelling, value in top.get("config", dict, {}).items()
    }
    try:
        config = apply_overrides(base_config, overrides, source + ": [config]")
    except ConfigError as config_error:
        raise ScenarioError(str(config_error)) from None
    steps_table = top.get("steps", list)
    steps = tuple(
        _next_to(_step(table, f"{source}: steps[{number}]"), source)
        for number, table in enumerate(steps_table)
    )
    expect = _Reader(
        top.get("expect", dict),
        source + ": [expect]",
        ("published", "responses", "results", "partials", "transcripts"),
    )
    published = expect.get("published", list)
    if not all(isinstance(text, str) for text in published):
        raise ScenarioError(f"{source}: [expect]: 'published' must be a list of strings")
    responses = expect.optional_list("responses", int, "integers (1 accepted, 0 rejected)")
    results = expect.optional_list("results", str, "strings")
    partials = expect.optional_list("partials", dict, 'tables such as { at = 0.75, text = "go to" }')
    transcripts = expect.optional_list("transcripts", dict, 'tables such as { text = "go", final = true }')
    voice = top.choice("voice", tuple(VOICES), "tones")
    for number, step in enumerate(steps):
        problem = VOICES[voice].problem_with(step.text) if isinstance(step, Say) else None
        if problem:
            raise ScenarioError(f"{source}: steps[{number}]: the {voice} voice {problem}")
    noise_db = top.get("background_noise_db", (int, float), None)
    return Scenario(
        name=top.get("name", str),
        source=source,
        config=config,
        steps=steps,
        expected=tuple(published),
        expected_responses=responses,
        expected_results=results,
        expected_partials=None
        if partials is None
        else tuple(
            _partial(table, f"{source}: [expect]: partials[{number}]")
            for number, table in enumerate(partials)
        ),
        expected_transcripts=None
        if transcripts is None
        else tuple(
            _transcript(table, f"{source}: [expect]: transcripts[{number}]")
            for number, table in enumerate(transcripts)
        ),
        voice=voice,
        recognizer=top.choice("recognizer", RECOGNIZERS, "fake"),
        background_noise_db=None if noise_db is None else float(noise_db),
        seed=int(top.get("seed", int, 0)),
    )


def _partial(table: Mapping[str, Any], where: str) -> ExpectedPartial:
    reader = _Reader(table, where, ("at", "text"))
    return ExpectedPartial(reader.seconds("at", allow_zero=True), reader.get("text", str))


def _transcript(table: Mapping[str, Any], where: str) -> Mapping[str, Any]:
    reader = _Reader(table, where, tuple(TRANSCRIPT_FIELDS))
    for key in ("text", "final"):
        reader.get(key, TRANSCRIPT_FIELDS[key])  # required
    return {key: reader.get(key, kind) for key, kind in TRANSCRIPT_FIELDS.items() if key in table}


def _from_folder(spelling: str, value: object, source: str) -> object:
    """A [config] value, a relative path taken from the scenario's folder when its key names a
    file, in any spelling (camelCase, pocketsphinx_grammar): a scenario's files are found next to
    it, wherever it is run from. ``fixture:`` models are built at test time."""
    if names_a_file(spelling) and isinstance(value, str) and value and not value.startswith(FIXTURE_PREFIX):
        return str(Path(source).parent / value)
    return value


def _next_to(step: Step, source: str) -> Step:
    """A step's files are found next to the scenario, as its [config] files are: a grammar step's,
    a recording, a noise file."""
    folder = Path(source).parent
    if isinstance(step, SetGrammar) and "|" not in step.request and (folder / step.request).is_file():
        return dataclasses.replace(step, request=str(folder / step.request))
    if isinstance(step, Play):
        path = _file_next_to(step.path, folder, source, "play")
        return dataclasses.replace(step, path=path, noise=_noise_next_to(step.noise, folder, source))
    if isinstance(step, Say):
        return dataclasses.replace(step, noise=_noise_next_to(step.noise, folder, source))
    if isinstance(step, Noise) and step.kind not in NOISE_KINDS:
        return dataclasses.replace(step, kind=_file_next_to(step.kind, folder, source, "kind"))
    return step


def _noise_next_to(masking: Optional[Masking], folder: Path, source: str) -> Optional[Masking]:
    if masking is None or masking.kind in NOISE_KINDS:
        return masking
    return Masking(_file_next_to(masking.kind, folder, source, "noise"), masking.snr_db)


def _file_next_to(name: str, folder: Path, source: str, key: str) -> str:
    path = folder / name
    if not path.is_file():
        allowed = "a sound file next to the scenario" + (
            f" or one of {', '.join(NOISE_KINDS)}" if key != "play" else ""
        )
        raise ScenarioError(f"{source}: {key} = {name!r}: there is no file {path}; allowed: {allowed}")
    return str(path)


def load_scenario(path: Union[str, Path], base_config: SpeechEventConfig) -> Scenario:
    try:
        document = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as problem:
        raise ScenarioError(f"{path}: cannot read the scenario: {problem.strerror}") from None
    except tomllib.TOMLDecodeError as problem:
        raise ScenarioError(f"{path}: not valid TOML: {problem}") from None
    return parse_scenario(document, str(path), base_config)


def add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    """SCENARIO and -c CONFIG, for the programs that play one scenario on ROS."""
    parser.add_argument("scenario", help="the scenario file")
    parser.add_argument("-c", "--config", help="configuration the scenario's [config] overrides")


def scenario_from_arguments(arguments: argparse.Namespace) -> Scenario:
    base = load_config(arguments.config) if arguments.config else SpeechEventConfig()
    return load_scenario(arguments.scenario, base)
