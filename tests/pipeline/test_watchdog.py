"""The recognition timeout alone (speech_event/pipeline/watchdog.py), on the fake clock."""

import logging
import threading
from typing import List, Set

import numpy as np
import pytest

from fixtures.fakes import SpyRecognizer, StoppableRecognizer
from speech_event.adapters.fake_clock import FakeClock
from speech_event.pipeline.recognition_queue import RecognitionJob
from speech_event.pipeline.watchdog import Watchdog
from speech_event.ports import Recognizer


class Running:
    """Which jobs run now, as the node would answer; records whether it was asked under the lock."""

    def __init__(self, lock: threading.Lock) -> None:
        self.lock = lock
        self.jobs: Set[int] = set()
        self.asked_under_lock: List[bool] = []

    def __call__(self, job: RecognitionJob) -> bool:
        self.asked_under_lock.append(self.lock.locked())
        return job.number in self.jobs


class Rig:
    def __init__(self, timeout: float) -> None:
        self.clock = FakeClock()
        self.lock = threading.Lock()
        self.running = Running(self.lock)
        self.watchdog = Watchdog(self.clock, self.lock, timeout, self.running)


def _job(recognizer: Recognizer, number: int = 7, seconds: float = 2.5) -> RecognitionJob:
    audio = np.zeros(int(seconds * 16000), dtype=np.float32)
    return RecognitionJob(number, 0.0, 0.0, 0.0, audio, recognizer, "english", seconds)


@pytest.mark.parametrize("timeout", [0.0, -1.0])
def test_no_timeout_sets_no_timer(timeout: float) -> None:
    rig = Rig(timeout)
    engine = StoppableRecognizer()
    rig.running.jobs.add(7)
    assert rig.watchdog.watch(_job(engine)) is None
    rig.clock.advance(3600.0)
    assert rig.watchdog.timed_out == 0
    assert engine.stops == 0
    assert rig.running.asked_under_lock == []


def test_a_recognition_still_running_at_the_timeout_is_stopped_and_counted() -> None:
    rig = Rig(30.0)
    engine = StoppableRecognizer()
    rig.running.jobs.add(7)
    rig.clock.advance(5.0)
    rig.watchdog.watch(_job(engine))
    rig.clock.advance_to(34.75)
    assert (rig.watchdog.timed_out, engine.stops) == (0, 0)
    rig.clock.advance_to(35.0)
    assert (rig.watchdog.timed_out, engine.stops) == (1, 1)


def test_the_overrun_is_logged_as_an_error_saying_it_is_cancelled(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(30.0)
    rig.running.jobs.add(7)
    rig.watchdog.watch(_job(StoppableRecognizer()))
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.clock.advance(30.0)
    assert [(record.levelno, record.getMessage()) for record in caplog.records] == [
        (
            logging.ERROR,
            "recognition of utterance 7 (2.50 s) still runs after recognition_timeout 30 s: cancelling it",
        )
    ]


def test_an_engine_that_cannot_be_stopped_is_only_counted_and_logged(
    caplog: pytest.LogCaptureFixture,
) -> None:
    rig = Rig(30.0)
    rig.running.jobs.add(7)
    rig.watchdog.watch(_job(SpyRecognizer()))
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.clock.advance(30.0)
    assert rig.watchdog.timed_out == 1
    assert [(record.levelno, record.getMessage()) for record in caplog.records] == [
        (
            logging.ERROR,
            "recognition of utterance 7 (2.50 s) still runs after recognition_timeout 30 s: "
            "this engine cannot be cancelled; later utterances wait, bounded by max_backlog",
        )
    ]


def test_a_recognition_that_ended_in_time_is_left_alone(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(30.0)
    engine = StoppableRecognizer()
    rig.watchdog.watch(_job(engine))  # the timer is not cancelled, but the job no longer runs
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.clock.advance(30.0)
    assert (rig.watchdog.timed_out, engine.stops) == (0, 0)
    assert caplog.records == []
    assert rig.running.asked_under_lock == [True]


def test_the_watchdog_asks_under_the_lock_about_the_job_it_watches() -> None:
    rig = Rig(30.0)
    engine = StoppableRecognizer()
    rig.running.jobs.add(8)  # another utterance runs now, not the one watched
    rig.watchdog.watch(_job(engine, number=7))
    rig.clock.advance(30.0)
    assert rig.running.asked_under_lock == [True]
    assert (rig.watchdog.timed_out, engine.stops) == (0, 0)


def test_a_cancelled_watch_never_fires() -> None:
    rig = Rig(30.0)
    engine = StoppableRecognizer()
    rig.running.jobs.add(7)
    timer = rig.watchdog.watch(_job(engine))
    assert timer is not None
    timer.cancel()
    rig.clock.advance(3600.0)
    assert (rig.watchdog.timed_out, engine.stops) == (0, 0)
    assert rig.running.asked_under_lock == []


def test_each_overrun_is_counted() -> None:
    rig = Rig(30.0)
    engine = StoppableRecognizer()
    rig.running.jobs.update({1, 2})
    rig.watchdog.watch(_job(engine, number=1))
    rig.clock.advance(10.0)
    rig.watchdog.watch(_job(engine, number=2))
    rig.clock.advance(30.0)
    assert (rig.watchdog.timed_out, engine.stops) == (2, 2)


def test_a_stop_waits_for_the_lock() -> None:
    """The timer fires while another thread holds the lock (a recognition ending): the watchdog
    asks nothing and stops nothing until that thread lets go."""
    rig = Rig(30.0)
    engine = StoppableRecognizer()
    rig.running.jobs.add(7)
    rig.watchdog.watch(_job(engine))
    rig.lock.acquire()
    mover = threading.Thread(target=rig.clock.advance, args=(30.0,))
    mover.start()
    try:
        mover.join(timeout=0.2)
        assert mover.is_alive()
        assert (rig.watchdog.timed_out, engine.stops) == (0, 0)
        rig.running.jobs.clear()  # the recognition ended under the lock
    finally:
        rig.lock.release()
    mover.join(timeout=30.0)
    assert not mover.is_alive()
    assert (rig.watchdog.timed_out, engine.stops) == (0, 0)
