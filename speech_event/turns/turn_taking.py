"""Turn-taking: when the utterance being collected ends, and when the speaker has paused enough to
speculate on it.

An utterance ends ``speech_pause_period`` after its latest block, or ``early_pause`` after it once
a speculation found a complete answer (early end of turn); each counts from when the callback that
took the block returned, if later than its arrival (TurnTaking.taken). Speculation may start
``speculation_gap`` after the latest block; with ``end_of_speech``, no block for that long is the end
of speech (the robot's gate), where the turn rules decide whether the turn ends. Each is one timer per
utterance, not one per block:
set at the first block, and when it fires early (more blocks came since) set again for the time
after the latest block; a block that arrives once the pause is over, before its timer fired, ends
the utterance first, and a block that arrived before it was over but still waits for the node's
lock keeps the timer from firing (ArrivingBlocks). Every method is called under the node's lock;
the timers take it.
"""

import functools
import math
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Callable, Iterator, List, Optional

from speech_event.config import (
    SpeechEventConfig,
    end_of_speech_seconds,
    ends_at_end_of_speech,
    speculation_gap_seconds,
)
from speech_event.ports import TIMER_TOLERANCE, Clock, Timer


@dataclass
class RearmingTimer:
    """Calls ``on_due`` under ``lock`` once the clock reaches ``due()``, which may move later."""

    clock: Clock
    lock: threading.Lock
    due: Callable[[], float]
    on_due: Callable[[], None]
    # The earliest arrival of a block that waits for the lock (ArrivingBlocks.earliest), if any.
    waiting: Callable[[], Optional[float]] = lambda: None
    _timer: Optional[Timer] = field(default=None, init=False)
    # Which setting of the timer is current: a timer thread that was already due when the timer
    # was cancelled (waiting for the lock meanwhile) must then do nothing.
    _setting: int = field(default=0, init=False)

    @property
    def armed(self) -> bool:
        """Whether the timer is set (it has not fired since it was)."""
        return self._timer is not None

    def arm(self) -> None:
        """Set the timer for ``due()``, unless it is set already."""
        if self._timer is None:
            self._setting += 1
            fire = functools.partial(self._fire, self._setting)
            self._timer = self.clock.call_at(max(self.clock.now(), self.due()), fire)

    def rearm(self) -> None:
        """Set the timer for ``due()`` now, which may be sooner than it was set for."""
        self.cancel()
        self.arm()

    def cancel(self) -> None:
        """Unset the timer."""
        timer, self._timer = self._timer, None
        if timer is not None:
            timer.cancel()

    def fire_if_over(self, at: float) -> None:
        """Under the lock: call ``on_due`` now if ``at`` (a block's arrival) is past ``due()`` but
        the timer has not fired yet (its thread is late: a busy machine)."""
        if self._timer is not None and at >= self.due():
            self.cancel()
            self.on_due()

    def _fire(self, setting: int) -> None:
        with self.lock:
            if self._timer is None or setting != self._setting:
                return
            self._timer = None
            if self.clock.now() < self.due() - TIMER_TOLERANCE:
                self.arm()
                return
            arrived = self.waiting()
            if arrived is not None and arrived < self.due():
                return  # a block came before it was due: taken, it sets the timer again
            self.on_due()


class ArrivingBlocks:
    """The blocks that have arrived and wait for the node's lock, by arrival. A timer whose thread
    takes the lock first must not hear a pause they were not part of: under load a block waited
    0.6 s while the worker took the blocks a decision had held, the end of speech was heard before
    it, and a reading was split where it paused for a comma (tests/real/test_driver_under_load.py).
    Its own lock, not the node's: a block counts as arrived before it waits for that."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._arrivals: List[float] = []

    @contextmanager
    def arriving(self, at: float) -> Iterator[None]:
        """While the block that arrived at ``at`` waits for the node's lock and is taken."""
        with self._lock:
            self._arrivals.append(at)
        try:
            yield
        finally:
            with self._lock:
                self._arrivals.remove(at)

    def earliest(self) -> Optional[float]:
        with self._lock:
            return min(self._arrivals, default=None)


class TurnTaking:
    """The pause that ends an utterance and the gap that lets speculation start, on one clock."""

    def __init__(
        self,
        config: SpeechEventConfig,
        clock: Clock,
        lock: threading.Lock,
        on_pause_end: Callable[[], None],
        on_gap: Callable[[], None],
        on_silence: Callable[[], None],
        on_speculated: Callable[[int, bool], None],
        deciding: Callable[[], bool] = lambda: True,
    ) -> None:
        """``on_pause_end`` closes the utterance; ``on_gap`` may speculate; ``on_silence`` (with
        end_of_speech) decides on the end of speech; ``on_speculated`` hears of each speculation on
        the utterance being collected (its samples, whether its text is complete). All four are
        called under ``lock``. ``deciding``: whether the end of speech decides with the engine and
        grammar in force now, which the gap left to its default follows."""
        self._config = config
        self._clock = clock
        self._on_speculated = on_speculated
        # With end_of_speech, while it decides, no block for that long is heard as the end of
        # speech (the robot's gate sends blocks only while it hears speech). A speculation on the
        # audio up to there may start sooner, at speculation_gap, so its text is ready when the end
        # is heard: one timer for each, the gap's only when it comes first. While it does not
        # decide, the timers are those of end_of_speech off.
        self._ends_at_end_of_speech = ends_at_end_of_speech(config)
        self._end_of_speech = end_of_speech_seconds(config)
        self._deciding = deciding
        self.last_arrival = 0.0
        # When the node had taken the latest block that came: later than its arrival when the
        # callback waited (for the lock, the CPU), and the next block could not come sooner.
        self._taken_at = 0.0
        self._ends_early = False  # this utterance's speculation is a complete answer
        self.waiting_blocks = ArrivingBlocks()
        waiting = self.waiting_blocks.earliest
        self._pause = RearmingTimer(clock, lock, self._pause_due, self._pause_ended(on_pause_end), waiting)
        self._gap = RearmingTimer(clock, lock, self._gap_due, on_gap, waiting)
        silence_heard = self._silence_heard(on_silence)
        self._silence = RearmingTimer(clock, lock, self._silence_due, silence_heard, waiting)

    def heard(self, when: float) -> None:
        """A block arrived at ``when``: the pause starts again, and the gap."""
        self.last_arrival = when
        self._ends_early = False
        self._pause.arm()
        silence = self._silence_seconds()
        if self._config.speculative_recognition and self._gap_seconds() < silence:
            self._gap.arm()
        if silence < math.inf:
            self._silence.arm()
        else:
            self._silence.cancel()

    def taken(self, when: float) -> None:
        """The callback that took the latest block returns at ``when``: the pause, the gap and
        end_of_speech count from then, not from the block's arrival. A source that publishes in
        the callback's thread (the driver on the in-memory bus) sends the next block after it
        returns: a callback that waited 0.33 s on a busy machine was followed by a gap of 0.33 s in
        the blocks, heard as the end of speech where nobody paused. (rospy stamps a block as it reads
        it: the node does not call this for those.)"""
        self._taken_at = when

    def end_pause_if_over(self, arrival: float) -> None:
        """Before a block that arrived at ``arrival`` is taken: if the pause after the latest block
        was over by then, the utterance ends now, although its timer has not fired yet, so the
        block starts the next utterance; and if end_of_speech without a block was over, the end of
        speech is heard (on_silence). Where utterances end then depends on when blocks arrive, never
        on how late a timer thread runs."""
        self._pause.fire_if_over(arrival)
        self._silence.fire_if_over(arrival)

    def speculated(self, samples: int, complete: bool) -> None:
        """A speculation on the first ``samples`` of the utterance being collected ended, its text
        complete by itself or not: a decision on the end of speech may wait for it."""
        self._on_speculated(samples, complete)

    def pause_again(self) -> None:
        """The pause's end waited for a decision: it ends on the clock's next turn if it is over."""
        self._pause.arm()

    def end_early(self) -> None:
        """A speculation found a complete answer: the turn ends after early_pause (when set)."""
        if self._config.early_pause <= 0:
            return
        self._ends_early = True
        self._pause.rearm()

    def gap_passed(self) -> bool:
        """Whether the speaker has paused for speculation_gap since the latest block."""
        return not self._gap.armed and self._clock.now() >= self._gap_due() - TIMER_TOLERANCE

    def drop_turn(self) -> None:
        """The utterance being collected is thrown away: no pause is waited for."""
        self._ends_early = False
        self._pause.cancel()

    def stop(self) -> None:
        """Unset both timers."""
        self._pause.cancel()
        self._gap.cancel()
        self._silence.cancel()

    def _since(self) -> float:
        """Since when no block came that the node could have taken."""
        return max(self.last_arrival, self._taken_at)

    def _pause_due(self) -> float:
        pause = self._config.early_pause if self._ends_early else self._config.speech_pause_period
        return self._since() + pause

    def _silence_seconds(self) -> float:
        """end_of_speech while it decides with the engine and grammar in force; else never."""
        return self._end_of_speech if self._ends_at_end_of_speech and self._deciding() else math.inf

    def _gap_seconds(self) -> float:
        return min(speculation_gap_seconds(self._config, self._deciding()), self._silence_seconds())

    def _gap_due(self) -> float:
        return self._since() + self._gap_seconds()

    def _silence_due(self) -> float:
        return self._since() + self._end_of_speech

    def _silence_heard(self, on_silence: Callable[[], None]) -> Callable[[], None]:
        def heard() -> None:  # a grammar may have been cleared since the timer was set
            if self._silence_seconds() < math.inf:
                on_silence()

        return heard

    def _pause_ended(self, close: Callable[[], None]) -> Callable[[], None]:
        def ended() -> None:
            self._ends_early = False
            close()

        return ended
