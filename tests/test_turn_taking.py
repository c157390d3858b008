"""Turn-taking alone (speech_event/turn_taking.py): RearmingTimer and TurnTaking on the fake clock.

Times are binary fractions, so every time the clock reaches is exact.
"""

import dataclasses
import threading
from typing import Callable, List, Tuple

from speech_event.adapters.fake_clock import FakeClock
from speech_event.config import SpeechEventConfig
from speech_event.turn_taking import TIMER_TOLERANCE, RearmingTimer, TurnTaking

# -- RearmingTimer ----------------------------------------------------------------------------------


class Due:
    """A due time the test moves, and the times the timer came due."""

    def __init__(self, clock: FakeClock, lock: threading.Lock, when: float) -> None:
        self.clock = clock
        self.lock = lock
        self.when = when
        self.fired: List[float] = []
        self.held_lock: List[bool] = []

    def __call__(self) -> float:
        return self.when

    def on_due(self) -> None:
        self.fired.append(self.clock.now())
        self.held_lock.append(self.lock.locked())


def _timer(when: float, start: float = 0.0) -> Tuple[FakeClock, Due, RearmingTimer]:
    clock = FakeClock(start)
    lock = threading.Lock()
    due = Due(clock, lock, when)
    return clock, due, RearmingTimer(clock, lock, due, due.on_due)


def test_the_timer_fires_once_at_its_due_time() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    clock.advance_to(1.75)
    assert due.fired == []
    clock.advance_to(2.0)
    assert due.fired == [2.0]
    clock.advance_to(10.0)
    assert due.fired == [2.0]


def test_the_timer_is_armed_until_it_fires() -> None:
    clock, _, timer = _timer(2.0)
    assert not timer.armed
    timer.arm()
    assert timer.armed
    clock.advance_to(2.0)
    assert not timer.armed


def test_arming_an_armed_timer_sets_no_second_timer() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    timer.arm()
    clock.advance_to(10.0)
    assert due.fired == [2.0]


def test_arming_an_armed_timer_keeps_its_time_even_if_due_moved_sooner() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    due.when = 1.0
    timer.arm()
    clock.advance_to(10.0)
    assert due.fired == [2.0]


def test_a_due_time_moved_later_rearms_the_timer_for_it() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    due.when = 3.5
    clock.advance_to(2.0)
    assert due.fired == []
    assert timer.armed
    clock.advance_to(10.0)
    assert due.fired == [3.5]


def test_a_due_time_moved_later_twice_fires_only_at_the_last_one() -> None:
    clock, due, timer = _timer(1.0)
    timer.arm()
    due.when = 2.0
    clock.advance_to(1.5)
    due.when = 3.0
    clock.advance_to(10.0)
    assert due.fired == [3.0]


def test_rearm_makes_the_timer_sooner() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    due.when = 0.5
    timer.rearm()
    clock.advance_to(10.0)
    assert due.fired == [0.5]


def test_rearm_of_an_unarmed_timer_arms_it() -> None:
    clock, due, timer = _timer(2.0)
    timer.rearm()
    clock.advance_to(10.0)
    assert due.fired == [2.0]


def test_cancel_stops_the_timer() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    timer.cancel()
    assert not timer.armed
    clock.advance_to(10.0)
    assert due.fired == []


def test_cancel_of_an_unarmed_timer_does_nothing() -> None:
    clock, due, timer = _timer(2.0)
    timer.cancel()
    clock.advance_to(10.0)
    assert due.fired == []
    assert not timer.armed


def test_a_cancelled_timer_can_be_armed_again() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    timer.cancel()
    timer.arm()
    clock.advance_to(10.0)
    assert due.fired == [2.0]


def test_a_due_time_already_past_fires_at_once() -> None:
    clock, due, timer = _timer(2.0, start=5.0)
    timer.arm()
    clock.advance(0.0)
    assert due.fired == [5.0]


def test_the_callback_runs_under_the_lock() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    clock.advance_to(2.0)
    assert due.held_lock == [True]


def test_the_tolerance_is_one_millisecond() -> None:
    assert TIMER_TOLERANCE == 1e-3


def test_a_timer_firing_less_than_the_tolerance_early_has_come_due() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    due.when = 2.0009  # the timer still fires at 2.0, 0.9 ms early
    clock.advance_to(10.0)
    assert due.fired == [2.0]


def test_a_timer_firing_more_than_the_tolerance_early_is_set_again() -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    due.when = 2.0011
    clock.advance_to(2.0)
    assert due.fired == []
    assert timer.armed
    clock.advance_to(10.0)
    assert due.fired == [2.0011]


class ManualClock:
    """A clock whose timers the test fires by hand, even cancelled ones: a timer thread (RosTimer,
    threading.Timer) that has passed its cancelled check and waits for the lock runs anyway."""

    def __init__(self) -> None:
        self.time = 0.0
        self.callbacks: List[Callable[[], None]] = []

    def now(self) -> float:
        return self.time

    def call_at(self, when: float, callback: Callable[[], None]) -> "ManualClock":
        self.callbacks.append(callback)
        return self

    def cancel(self) -> None:
        pass


def test_a_callback_of_a_timer_cancelled_while_it_waited_for_the_lock_does_nothing() -> None:
    clock = ManualClock()
    lock = threading.Lock()
    fired: List[float] = []
    timer = RearmingTimer(clock, lock, lambda: 2.0, lambda: fired.append(clock.now()))
    timer.arm()
    clock.time = 2.0  # the timer thread is due, and waits for the lock the node holds:
    timer.cancel()  # the node cancels it (drop_turn, stop) under that lock
    stale = clock.callbacks[0]
    stale()  # the lock is free again: the thread runs its callback
    assert fired == []


# -- TurnTaking -------------------------------------------------------------------------------------

CONFIG = SpeechEventConfig(speech_pause_period=1.5, speculation_gap=0.25, early_pause=0.0)
EARLY = dataclasses.replace(CONFIG, early_pause=0.5)


class Turn:
    """TurnTaking on a fake clock, with the times its pause ended and its gap passed."""

    def __init__(self, config: SpeechEventConfig) -> None:
        self.clock = FakeClock()
        self.lock = threading.Lock()
        self.ends: List[float] = []
        self.gaps: List[float] = []
        self.gap_passed_at_gap: List[bool] = []
        self.held_lock: List[bool] = []
        self.turn = TurnTaking(config, self.clock, self.lock, self._ended, self._gap)

    def _ended(self) -> None:
        self.ends.append(self.clock.now())
        self.held_lock.append(self.lock.locked())

    def _gap(self) -> None:
        self.gaps.append(self.clock.now())
        self.held_lock.append(self.lock.locked())
        self.gap_passed_at_gap.append(self.turn.gap_passed())

    def block(self, when: float) -> None:
        """A block arrives at ``when``."""
        self.clock.advance_to(when)
        self.turn.heard(when)


def test_one_block_ends_the_utterance_speech_pause_period_after_it() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.clock.advance_to(1.25)
    assert turn.ends == []
    turn.clock.advance_to(10.0)
    assert turn.ends == [1.5]


def test_the_pause_ends_speech_pause_period_after_the_last_block() -> None:
    turn = Turn(CONFIG)
    for when in (0.0, 0.5, 1.0, 1.25):
        turn.block(when)
    turn.clock.advance_to(2.5)
    assert turn.ends == []
    turn.clock.advance_to(10.0)
    assert turn.ends == [2.75]


def test_heard_records_the_last_arrival() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.block(0.75)
    assert turn.turn.last_arrival == 0.75


def test_the_pause_and_the_gap_call_back_under_the_lock() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.clock.advance_to(10.0)
    assert turn.gaps == [0.25]
    assert turn.ends == [1.5]
    assert turn.held_lock == [True, True]


def test_each_utterance_has_its_own_pause() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.block(2.0)
    turn.clock.advance_to(10.0)
    assert turn.ends == [1.5, 3.5]


def test_a_complete_answer_ends_the_turn_early_pause_after_the_last_block() -> None:
    turn = Turn(EARLY)
    turn.block(0.0)
    turn.block(0.125)
    turn.clock.advance_to(0.375)  # the speculation, from the gap at 0.375, says a complete answer
    turn.turn.end_early()
    turn.clock.advance_to(10.0)
    assert turn.ends == [0.625]


def test_a_complete_answer_found_after_early_pause_ends_the_turn_at_once() -> None:
    turn = Turn(EARLY)
    turn.block(0.0)
    turn.clock.advance_to(0.75)
    turn.turn.end_early()
    turn.clock.advance(0.0)
    assert turn.ends == [0.75]


def test_with_early_pause_0_a_complete_answer_changes_nothing() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.clock.advance_to(0.25)
    turn.turn.end_early()
    turn.clock.advance_to(10.0)
    assert turn.ends == [1.5]


def test_a_block_after_the_complete_answer_brings_back_the_whole_pause() -> None:
    turn = Turn(EARLY)
    turn.block(0.0)
    turn.clock.advance_to(0.25)
    turn.turn.end_early()
    turn.block(0.375)
    turn.clock.advance_to(10.0)
    assert turn.ends == [1.875]


def test_the_utterance_after_an_early_end_waits_the_whole_pause() -> None:
    turn = Turn(EARLY)
    turn.block(0.0)
    turn.clock.advance_to(0.25)
    turn.turn.end_early()
    turn.clock.advance_to(1.0)
    turn.block(2.0)
    turn.clock.advance_to(10.0)
    assert turn.ends == [0.5, 3.5]


def test_the_gap_passes_speculation_gap_after_the_last_block() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.block(0.125)
    turn.clock.advance_to(0.25)
    assert turn.gaps == []
    turn.clock.advance_to(1.0)
    assert turn.gaps == [0.375]
    assert turn.gap_passed_at_gap == [True]


def test_the_gap_passes_once_per_pause() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.block(0.5)
    turn.clock.advance_to(10.0)
    assert turn.gaps == [0.25, 0.75]


def test_without_speculative_recognition_the_gap_sets_no_timer() -> None:
    turn = Turn(dataclasses.replace(CONFIG, speculative_recognition=False))
    turn.block(0.0)
    turn.clock.advance_to(10.0)
    assert turn.gaps == []
    assert turn.ends == [1.5]


def test_gap_passed_is_false_while_the_gap_timer_waits() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.block(0.125)
    turn.clock.advance_to(0.3125)  # the first gap timer fired at 0.25 and was set again for 0.375
    assert not turn.turn.gap_passed()
    turn.clock.advance_to(0.375)
    assert turn.turn.gap_passed()


def test_gap_passed_comes_exactly_at_the_gap_less_the_tolerance() -> None:
    turn = Turn(dataclasses.replace(CONFIG, speculative_recognition=False))  # no timer: the clock alone
    turn.block(0.0)
    turn.clock.advance_to(0.2489)
    assert not turn.turn.gap_passed()
    turn.clock.advance_to(0.2491)
    assert turn.turn.gap_passed()


def test_drop_turn_waits_for_no_pause() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.turn.drop_turn()
    turn.clock.advance_to(10.0)
    assert turn.ends == []


def test_drop_turn_leaves_the_gap_timer_set() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.turn.drop_turn()
    turn.clock.advance_to(10.0)
    assert turn.gaps == [0.25]


def test_drop_turn_forgets_an_early_end() -> None:
    turn = Turn(EARLY)
    turn.block(0.0)
    turn.clock.advance_to(0.25)
    turn.turn.end_early()
    turn.turn.drop_turn()
    turn.clock.advance_to(1.0)
    assert turn.ends == []
    turn.block(2.0)
    turn.clock.advance_to(10.0)
    assert turn.ends == [3.5]


def test_the_next_block_after_drop_turn_starts_a_whole_pause() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.turn.drop_turn()
    turn.block(1.0)
    turn.clock.advance_to(10.0)
    assert turn.ends == [2.5]


def test_stop_unsets_both_timers() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.turn.stop()
    turn.clock.advance_to(10.0)
    assert turn.ends == []
    assert turn.gaps == []
