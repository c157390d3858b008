"""What the node has done, counted, and the ``/diagnostics`` status built from it.

Every ``health_check_period`` the node publishes one ``diagnostic_msgs/DiagnosticArray`` with one
status named for the node: ERROR when soundDetection is down, WARN when utterances wait behind a
running recognition (it cannot keep up), otherwise OK; and key-values that
``rostopic echo /diagnostics`` and ``rqt_runtime_monitor`` show.
"""

import threading
from dataclasses import dataclass, field
from typing import Dict, List, Tuple

from speech_event.grammar import FREE_SPEECH
from speech_event.messages import DiagnosticArray, DiagnosticStatus, KeyValue
from speech_event.ports import PublisherStatus

DIAGNOSTICS_TOPIC = "/diagnostics"
STATUS_NAME = "speechEvent"
# Why an utterance was not transcribed: the node was disabled, and the speech screen's reasons.
DISCARDED_WHILE_DISABLED = "disabled"
DISCARDED_BACKLOG = "backlog"  # dropped unrecognized to keep within max_backlog
# The room after a turn that ended at the end of speech, with no speech heard in it (end_of_turn.py).
DISCARDED_AFTER_SPEECH = "no_speech_after_turn"
PARTIAL_WORKER_KEY = "partial results worker time (s)"


@dataclass
class _Counts:
    transcribed: int = 0
    published: int = 0
    out_of_grammar: int = 0  # speech judged to be no phrase of the grammar in force
    discarded: Dict[str, int] = field(default_factory=dict)
    ignored_while_disabled: int = 0
    recognition_seconds: List[float] = field(default_factory=list)
    audio_seconds: List[float] = field(default_factory=list)
    waiting: int = 0  # utterances handed to recognition and not done yet
    waiting_audio_seconds: float = 0.0


@dataclass(frozen=True)
class NodeState:
    """What the node says about itself when the status is built."""

    engine: str
    language: str
    enabled: bool
    sound_detection: PublisherStatus
    rejected: Dict[str, int]
    grammar: str = ""  # the grammar in force (its file or phrases); "" for free speech
    clipped: int = 0
    timed_out: int = 0  # recognitions that ran past recognition_timeout
    utterances: int = 0  # closed so far
    queued_seconds: float = 0.0  # of speech waiting for recognition
    dropped: int = 0  # utterances dropped unrecognized (max_backlog)
    partials_published: int = 0  # on /speechEvent/partial
    partial_seconds: float = 0.0  # of engine time the partial results took


class NodeStatistics:
    """Counters the node's threads update; each method takes the statistics' own lock."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._counts = _Counts()

    def queued(self, audio_seconds: float) -> None:
        with self._lock:
            self._counts.waiting += 1
            self._counts.waiting_audio_seconds += audio_seconds

    def finished(self, audio_seconds: float) -> None:
        with self._lock:
            self._counts.waiting -= 1
            self._counts.waiting_audio_seconds = max(0.0, self._counts.waiting_audio_seconds - audio_seconds)

    def transcribed(self, audio_seconds: float, recognition_seconds: float) -> None:
        with self._lock:
            self._counts.transcribed += 1
            self._counts.audio_seconds.append(audio_seconds)
            self._counts.recognition_seconds.append(recognition_seconds)

    def published(self) -> None:
        with self._lock:
            self._counts.published += 1

    def out_of_grammar(self) -> None:
        with self._lock:
            self._counts.out_of_grammar += 1

    def discarded(self, reason: str) -> None:
        with self._lock:
            self._counts.discarded[reason] = self._counts.discarded.get(reason, 0) + 1

    def ignored_while_disabled(self) -> None:
        with self._lock:
            self._counts.ignored_while_disabled += 1

    def status(self, state: NodeState, discard_reasons: List[str]) -> DiagnosticStatus:
        with self._lock:
            counts = self._counts
            values: List[KeyValue] = [
                KeyValue("engine", state.engine),
                KeyValue("language", state.language),
                KeyValue("enabled", str(state.enabled).lower()),
                KeyValue("soundDetection", state.sound_detection.value),
                KeyValue("utterances transcribed", str(counts.transcribed)),
                KeyValue("texts published", str(counts.published)),
                KeyValue("grammar", state.grammar or FREE_SPEECH),
                KeyValue("utterances out of grammar", str(counts.out_of_grammar)),
            ]
            values += [
                KeyValue(f"utterances discarded: {reason}", str(counts.discarded.get(reason, 0)))
                for reason in [
                    DISCARDED_WHILE_DISABLED,
                    *discard_reasons,
                    DISCARDED_AFTER_SPEECH,
                    DISCARDED_BACKLOG,
                ]
            ]
            values.append(KeyValue("messages ignored while disabled", str(counts.ignored_while_disabled)))
            values += [
                KeyValue(f"rejected messages: {reason}", str(n)) for reason, n in state.rejected.items()
            ]
            values.append(KeyValue("clipped messages", str(state.clipped)))
            values += _timing(counts.recognition_seconds, counts.audio_seconds)
            values += [
                KeyValue("utterances waiting for recognition", str(counts.waiting)),
                KeyValue("queued audio (s)", f"{counts.waiting_audio_seconds:.3f}"),
                KeyValue("recognitions timed out", str(state.timed_out)),
                KeyValue("partial results published", str(state.partials_published)),
                KeyValue(PARTIAL_WORKER_KEY, f"{state.partial_seconds:.3f}"),
            ]
            backlog = counts.waiting - 1
        level, message = _level(state, backlog)
        return DiagnosticStatus(level, STATUS_NAME, message, "", tuple(values))


def _timing(recognition: List[float], audio: List[float]) -> List[KeyValue]:
    if not recognition:
        return [KeyValue(key, "none yet") for key in _TIMING_KEYS]
    last_rtf = recognition[-1] / audio[-1] if audio[-1] > 0 else 0.0
    total_audio = sum(audio)
    mean_rtf = sum(recognition) / total_audio if total_audio > 0 else 0.0
    figures = (recognition[-1], sum(recognition) / len(recognition), last_rtf, mean_rtf)
    return [KeyValue(key, f"{figure:.4f}") for key, figure in zip(_TIMING_KEYS, figures)]


_TIMING_KEYS = (
    "last recognition time (s)",
    "mean recognition time (s)",
    "last real-time factor",
    "mean real-time factor",
)


def _level(state: NodeState, backlog: int) -> Tuple[int, str]:
    if not state.sound_detection.up:
        return DiagnosticStatus.ERROR, f"soundDetection is down: {state.sound_detection.value}"
    if backlog > 0:
        return DiagnosticStatus.WARN, f"recognition backlog: {backlog} utterances wait behind the running one"
    return DiagnosticStatus.OK, "listening" if state.enabled else "disabled"


def diagnostic_array(stamp: float, status: DiagnosticStatus) -> DiagnosticArray:
    """The /diagnostics message: the node's one status, stamped with the node's clock."""
    return DiagnosticArray(stamp, (status,))
