"""Runtime control: the services the robot's Behaviour Controller calls.

``/speechEvent/set_enabled`` (``string status`` -> ``int8 response``): "true" or "false", trimmed,
in any case, answers 1; anything else answers 0 with a warning naming what is allowed. The robot
disables the node while it speaks, so it never transcribes its own voice.

``/speechEvent/set_language`` (``string language`` -> ``int8 response``): "english" or
"kinyarwanda", trimmed, in any case ("English" is what the Behaviour Controller sends). The new
language's engine is built here, on the service's thread; one that cannot be built, or cannot take
the grammar in force, answers 0, says why, and the old language goes on.

``/speechEvent/set_grammar`` (``string grammar`` -> ``int8 response``): a JSGF or phrase file, phrases
parted by ``|`` ("yes|no" for one question), or empty for free speech again (speech_event/grammar.py).
It is checked against the engine in use (words it cannot spell); one that cannot be used answers 0,
says why, and the grammar in force stays. Utterances closed before the switch finish with the old one.
"""

import logging
from pathlib import Path
from typing import Callable, Optional, Tuple

from speech_event.config import SpeechEventConfig
from speech_event.errors import ConfigError, GrammarError, ModelError
from speech_event.grammar import FREE_SPEECH, Grammar, load_grammar, requested_grammar
from speech_event.interfaces.language_engines import LanguageEngines
from speech_event.messages import SetEnabledResponse, SetGrammarResponse, SetLanguageResponse
from speech_event.ports import Grammars, Recognizer, engine_name

_LOG = logging.getLogger("speech_event")

SET_ENABLED_SERVICE = "/speechEvent/set_enabled"
SET_LANGUAGE_SERVICE = "/speechEvent/set_language"
SET_GRAMMAR_SERVICE = "/speechEvent/set_grammar"
ENABLED_VALUES = {"true": True, "false": False}
LANGUAGES = ("english", "kinyarwanda")
ACCEPTED, REJECTED = 1, 0


class RuntimeControl:
    """Answers set_enabled, set_language and set_grammar: checks the request, then enables, disables,
    switches engine or grammar through the node's callbacks."""

    def __init__(
        self,
        engines: LanguageEngines,
        current: Callable[[], Tuple[str, Recognizer, Optional[Grammar]]],
        set_enabled: Callable[[bool], None],
        use_engine: Callable[[str, Recognizer], None],
        use_grammar: Callable[[Optional[Grammar]], None],
    ) -> None:
        """``current`` gives the language, the engine and the grammar in force now."""
        self._engines = engines
        self._current = current
        self._set_enabled = set_enabled
        self._use_engine = use_engine
        self._use_grammar = use_grammar

    def _current_language(self) -> str:
        return self._current()[0]

    def on_set_enabled(self, request: object) -> SetEnabledResponse:
        status = _allowed(request, "status", tuple(ENABLED_VALUES), SET_ENABLED_SERVICE)
        if status is None:
            return SetEnabledResponse(REJECTED)
        self._set_enabled(ENABLED_VALUES[status])
        return SetEnabledResponse(ACCEPTED)

    def on_set_language(self, request: object) -> SetLanguageResponse:
        language = _allowed(request, "language", LANGUAGES, SET_LANGUAGE_SERVICE)
        if language is None:
            return SetLanguageResponse(REJECTED)
        if language == self._current_language():
            return SetLanguageResponse(ACCEPTED)
        try:
            engine = self._engines.engine(language)
            grammar = self._current()[2]
            reason = None if grammar is None else cannot_use(engine, grammar)
        except ModelError as problem:
            reason = str(problem)
        except Exception:  # a broken model file can fail in the runtime's own ways
            _LOG.exception(
                "%s: cannot switch to %s, staying with %s",
                SET_LANGUAGE_SERVICE,
                language,
                self._current_language(),
            )
            return SetLanguageResponse(REJECTED)
        if reason is not None:  # no engine, or one that cannot take the grammar in force
            _LOG.error(
                "%s: cannot switch to %s, staying with %s: %s",
                SET_LANGUAGE_SERVICE,
                language,
                self._current_language(),
                reason,
            )
            return SetLanguageResponse(REJECTED)
        self._use_engine(language, engine)
        return SetLanguageResponse(ACCEPTED)

    def on_set_grammar(self, request: object) -> SetGrammarResponse:
        asked = getattr(request, "grammar", None)
        if not isinstance(asked, str):
            _LOG.warning(
                "%s: grammar %r is not text; allowed: %s", SET_GRAMMAR_SERVICE, asked, ALLOWED_GRAMMAR
            )
            return SetGrammarResponse(REJECTED)
        try:
            grammar = requested_grammar(asked)
        except GrammarError as problem:
            _LOG.warning("%s: %s", SET_GRAMMAR_SERVICE, problem)
            return SetGrammarResponse(REJECTED)
        _, engine, in_force = self._current()
        reason = None if grammar is None else cannot_use(engine, grammar)
        if reason is not None:
            _LOG.warning(
                "%s: %s; the grammar in force stays: %s",
                SET_GRAMMAR_SERVICE,
                reason,
                FREE_SPEECH if in_force is None else in_force.source,
            )
            return SetGrammarResponse(REJECTED)
        self._use_grammar(grammar)
        return SetGrammarResponse(ACCEPTED)


ALLOWED_GRAMMAR = "a JSGF or phrase file, phrases parted by |, or empty for free speech"


def cannot_use(engine: Recognizer, grammar: Grammar) -> Optional[str]:
    """Why ``engine`` cannot decode within ``grammar``, or None when it can."""
    if not isinstance(engine, Grammars):
        return f"the {engine_name(engine)} engine takes no grammar"
    try:
        engine.check_grammar(grammar)
    except GrammarError as problem:
        return str(problem)
    return None


def starting_grammar(config: SpeechEventConfig, recognizer: Recognizer) -> Optional[Grammar]:
    """The grammar in force when the node starts: the ``grammar`` key's, checked against the engine
    as set_grammar checks one; None for free speech. ConfigError when it cannot be read or used."""
    if not config.grammar:
        return None
    try:
        grammar = load_grammar(Path(config.grammar))
    except GrammarError as problem:
        raise ConfigError(f"grammar: {problem}") from None
    reason = cannot_use(recognizer, grammar)
    if reason is not None:
        raise ConfigError(f"grammar {config.grammar}: {reason}")
    return grammar


def _allowed(request: object, field: str, allowed: Tuple[str, ...], service: str) -> Optional[str]:
    """The request's ``field``, trimmed and in lower case, if it is one of ``allowed``; else None,
    with a warning that names what is allowed."""
    value = str(getattr(request, field, "")).strip().lower()
    if value in allowed:
        return value
    _LOG.warning(
        "%s: %s %r is not allowed; allowed: %s (any case)",
        service,
        field,
        getattr(request, field, None),
        " or ".join(allowed),
    )
    return None
