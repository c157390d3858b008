"""The speech engine of each language: the configured one, and the other built when it is asked for.

``set_language`` builds the other language's engine on the service's own thread (never the
subscriber callback, never the recognition worker), once: a later switch back and forth reuses it.
"""

import threading
from typing import Dict, Optional

from speech_event.errors import ModelError
from speech_event.ports import EngineBuilder, Recognizer


class LanguageEngines:
    """The engine of each language, each built once, the first time it is asked for."""

    def __init__(self, language: str, recognizer: Recognizer, build: Optional[EngineBuilder] = None) -> None:
        self._engines: Dict[str, Recognizer] = {language: recognizer}
        self._build = build
        # Two set_language calls at once build an engine once.
        self._lock = threading.Lock()

    def engine(self, language: str) -> Recognizer:
        """The engine of ``language``, built now if it was not yet; ModelError if it cannot be."""
        with self._lock:
            if language not in self._engines:
                if self._build is None:
                    raise ModelError(f"this node was started with no way to build a {language} engine")
                self._engines[language] = self._build(language)
            return self._engines[language]
