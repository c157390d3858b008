"""The recognition worker, as the jobs handed to it see it: closed utterances
(closed_utterances.py) and the background runs (speech_event/turns/background_runs.py)."""

from dataclasses import dataclass
from typing import Callable

from speech_event.pipeline.publication import Publishes
from speech_event.pipeline.recognition import Recognize
from speech_event.pipeline.watchdog import Watchdog
from speech_event.ports import Executor


@dataclass(frozen=True)
class Worker:
    """What the worker's jobs run on and end in."""

    executor: Executor  # runs the jobs one at a time, in the order they came
    recognize: Recognize
    stopwatch: Callable[[], float]  # times what is no Recognition (a partial feed), for diagnostics
    publication: Publishes
    watchdog: Watchdog  # recognition_timeout over a closed utterance's recognition
