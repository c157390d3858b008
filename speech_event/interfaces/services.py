"""Runtime control: the services the robot's Behaviour Controller calls.

``/speechEvent/set_enabled`` (``string status`` -> ``int8 response``): "true" or "false", trimmed,
in any case, answers 1; anything else answers 0 with a warning naming what is allowed. The robot
disables the node while it speaks, so it never transcribes its own voice.

``/speechEvent/set_language`` (``string language`` -> ``int8 response``): "english" or
"kinyarwanda", trimmed, in any case ("English" is what the Behaviour Controller sends). The new
language's engine is built here, on the service's thread; one that cannot be built answers 0, says
why, and the old language goes on.
"""

import logging
from typing import Callable, Optional, Tuple

from speech_event.errors import ModelError
from speech_event.interfaces.language_engines import LanguageEngines
from speech_event.messages import SetEnabledResponse, SetLanguageResponse
from speech_event.ports import Recognizer

_LOG = logging.getLogger("speech_event")

SET_ENABLED_SERVICE = "/speechEvent/set_enabled"
SET_LANGUAGE_SERVICE = "/speechEvent/set_language"
ENABLED_VALUES = {"true": True, "false": False}
LANGUAGES = ("english", "kinyarwanda")
ACCEPTED, REJECTED = 1, 0


class RuntimeControl:
    """Answers set_enabled and set_language: checks the request, then enables, disables or switches engine."""

    def __init__(
        self,
        engines: LanguageEngines,
        current_language: Callable[[], str],
        set_enabled: Callable[[bool], None],
        use_engine: Callable[[str, Recognizer], None],
    ) -> None:
        self._engines = engines
        self._current_language = current_language
        self._set_enabled = set_enabled
        self._use_engine = use_engine

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
        except ModelError as problem:
            _LOG.error(
                "%s: cannot switch to %s, staying with %s: %s",
                SET_LANGUAGE_SERVICE,
                language,
                self._current_language(),
                problem,
            )
            return SetLanguageResponse(REJECTED)
        except Exception:  # a broken model file can fail in the runtime's own ways
            _LOG.exception(
                "%s: cannot switch to %s, staying with %s",
                SET_LANGUAGE_SERVICE,
                language,
                self._current_language(),
            )
            return SetLanguageResponse(REJECTED)
        self._use_engine(language, engine)
        return SetLanguageResponse(ACCEPTED)


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
