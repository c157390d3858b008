"""pocketsphinx in a process of its own: what the ``pocketsphinx`` and ``auto`` engines run.

Its binding holds the GIL for a whole decoding (engine_process.py says what that did to the node),
so the node's process never runs it: SphinxRecognizer is built and called in a child, with the
ports it implements (Grammars, Incremental; not Stoppable) and ``last_ratio``.
"""

import functools
from typing import Optional, cast

from speech_event.grammar import Grammar
from speech_event.recognizers.hosted import HostedGrammars, HostedIncremental
from speech_event.recognizers.sphinx import SphinxRecognizer


class SphinxProcess(HostedGrammars, HostedIncremental):
    """SphinxRecognizer, with the same arguments, in a child process."""

    def __init__(
        self,
        grammar: Optional[Grammar] = None,
        keywords: str = "",
        grammar_threshold: Optional[float] = None,
    ) -> None:
        """Starts the child and builds the engine there: its ModelError is raised here."""
        factory = functools.partial(SphinxRecognizer, grammar, keywords, grammar_threshold)
        super().__init__("pocketsphinx", factory)

    @property
    def last_ratio(self) -> Optional[float]:
        """SphinxRecognizer.last_ratio: the ratio the last transcribe within a grammar judged by."""
        return cast(Optional[float], self.process.read("last_ratio"))
