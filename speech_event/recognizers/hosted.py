"""The ports of an engine hosted in an EngineProcess (engine_process.py), one class each.

The node finds an engine's abilities with ``isinstance`` (speech_event/ports.py), so a hosted
engine's class combines exactly the classes of the ports its engine implements: ``HostedRecognizer``
always, ``HostedGrammars`` and ``HostedIncremental`` as the engine has them. None is Stoppable: a
hosted call cannot be stopped halfway. Each is ``Hosted``: transcripts name the engine it runs.
"""

from types import TracebackType
from typing import Optional, Tuple, Type, TypeVar, cast

from speech_event.grammar import Grammar
from speech_event.ports import Audio, Transcript
from speech_event.recognizers.engine_process import EngineFactory, EngineProcess

_Self = TypeVar("_Self", bound="HostedRecognizer")


class HostedRecognizer:
    """The Recognizer port of the engine ``factory`` builds, in a process of its own (started
    here; ``close()`` or the end of a ``with`` block ends it)."""

    # The methods whose last call is made again on a child started after one died: they set state.
    _replayed: Tuple[str, ...] = ()

    def __init__(self, name: str, factory: EngineFactory) -> None:
        self.process = EngineProcess(name, factory, self._replayed)
        self._sample_rate = int(self.process.read("sample_rate"))  # fixed: read once

    @property
    def hosts(self) -> str:
        """The class name of the engine it runs (the Hosted port): what transcripts call it."""
        return self.process.engine_class

    @property
    def sample_rate(self) -> int:
        """The rate, in Hz, of the audio ``transcribe`` expects."""
        return self._sample_rate

    def transcribe(self, audio: Audio) -> Transcript:
        """Transcribe one utterance of mono float32 audio at ``sample_rate``."""
        return cast(Transcript, self.process.call("transcribe", audio))

    def close(self) -> None:
        """End the engine's process."""
        self.process.close()

    def __enter__(self: _Self) -> _Self:
        return self

    def __exit__(
        self,
        kind: Optional[Type[BaseException]],
        error: Optional[BaseException],
        trace: Optional[TracebackType],
    ) -> None:
        self.close()


class HostedGrammars(HostedRecognizer):
    """The Grammars port, forwarded."""

    _replayed = ("use_grammar",)

    def check_grammar(self, grammar: Grammar) -> None:
        """GrammarError saying why the engine cannot use ``grammar``."""
        self.process.call("check_grammar", grammar)

    def use_grammar(self, grammar: Optional[Grammar]) -> None:
        """Decode within ``grammar`` from the next ``transcribe`` on; None: free speech again."""
        self.process.call("use_grammar", grammar)


class HostedIncremental(HostedRecognizer):
    """The Incremental port, forwarded. A partial utterance begun on a child that died is not on
    the next one: the engine says so when it is fed (SphinxRecognizer.feed_partial)."""

    def begin_partial(self, grammar: Optional[Grammar]) -> None:
        """A new utterance on the engine's partial decoder, within ``grammar``."""
        self.process.call("begin_partial", grammar)

    def feed_partial(self, audio: Audio) -> Transcript:
        """The next samples of the utterance: the text of all of it so far."""
        return cast(Transcript, self.process.call("feed_partial", audio))
