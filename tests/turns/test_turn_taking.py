"""Turn-taking alone (speech_event/turns/turn_taking.py): RearmingTimer and TurnTaking on the fake clock.

Times are binary fractions, so every time the clock reaches is exact.
"""

import dataclasses
import threading
from typing import Callable, List, NamedTuple, Sequence, Tuple, Union

import pytest

from speech_event.adapters.fake_clock import FakeClock
from speech_event.config import SpeechEventConfig
from speech_event.ports import TIMER_TOLERANCE
from speech_event.turns.turn_taking import ArrivingBlocks, RearmingTimer, TurnTaking

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


TimerStep = Union[float, Callable[[RearmingTimer], None]]
ARM, REARM, CANCEL = RearmingTimer.arm, RearmingTimer.rearm, RearmingTimer.cancel


def _operate(due: Due, timer: RearmingTimer, steps: Sequence[TimerStep]) -> None:
    """Each step: the due time moves to that time (a float), or an operation on the timer."""
    for step in steps:
        if isinstance(step, float):
            due.when = step
        else:
            step(timer)


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


@pytest.mark.parametrize(
    ("steps", "fired"),
    [
        pytest.param([ARM, ARM], [2.0], id="arming_an_armed_timer_sets_no_second_timer"),
        pytest.param(
            [ARM, 1.0, ARM], [2.0], id="arming_an_armed_timer_keeps_its_time_even_if_due_moved_sooner"
        ),
        pytest.param([ARM, 0.5, REARM], [0.5], id="rearm_makes_the_timer_sooner"),
        pytest.param([REARM], [2.0], id="rearm_of_an_unarmed_timer_arms_it"),
        pytest.param([ARM, CANCEL, ARM], [2.0], id="a_cancelled_timer_can_be_armed_again"),
        # the timer still fires at 2.0, 0.9 ms early
        pytest.param([ARM, 2.0009], [2.0], id="a_timer_firing_less_than_the_tolerance_early_has_come_due"),
    ],
)
def test_the_timer_due_at_2_fires_once(steps: List[TimerStep], fired: List[float]) -> None:
    clock, due, timer = _timer(2.0)
    _operate(due, timer, steps)
    clock.advance_to(10.0)
    assert due.fired == fired


@pytest.mark.parametrize(
    "later",
    [
        pytest.param(3.5, id="a_due_time_moved_later_rearms_the_timer_for_it"),
        pytest.param(2.0011, id="a_timer_firing_more_than_the_tolerance_early_is_set_again"),
    ],
)
def test_a_due_time_moved_later_sets_the_timer_again(later: float) -> None:
    clock, due, timer = _timer(2.0)
    timer.arm()
    due.when = later
    clock.advance_to(2.0)
    assert due.fired == []
    assert timer.armed
    clock.advance_to(10.0)
    assert due.fired == [later]


def test_a_due_time_moved_later_twice_fires_only_at_the_last_one() -> None:
    clock, due, timer = _timer(1.0)
    timer.arm()
    due.when = 2.0
    clock.advance_to(1.5)
    due.when = 3.0
    clock.advance_to(10.0)
    assert due.fired == [3.0]


@pytest.mark.parametrize(
    "steps",
    [
        pytest.param([ARM, CANCEL], id="cancel_stops_the_timer"),
        pytest.param([CANCEL], id="cancel_of_an_unarmed_timer_does_nothing"),
    ],
)
def test_a_cancelled_timer_is_unarmed_and_never_fires(steps: List[TimerStep]) -> None:
    clock, due, timer = _timer(2.0)
    _operate(due, timer, steps)
    assert not timer.armed
    clock.advance_to(10.0)
    assert due.fired == []
    assert not timer.armed


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


def test_a_timer_over_due_fires_when_asked_and_its_late_thread_then_does_nothing() -> None:
    clock = ManualClock()
    lock = threading.Lock()
    fired: List[float] = []
    timer = RearmingTimer(clock, lock, lambda: 2.0, lambda: fired.append(clock.now()))
    timer.arm()
    timer.fire_if_over(1.999)
    assert fired == []
    clock.time = 2.0  # due, but its thread has not run (a busy machine)
    timer.fire_if_over(2.0)
    assert fired == [2.0]
    assert not timer.armed
    clock.callbacks[0]()  # the late thread runs at last
    assert fired == [2.0]


def test_fire_if_over_leaves_an_unarmed_timer_alone() -> None:
    clock = ManualClock()
    fired: List[float] = []
    timer = RearmingTimer(clock, threading.Lock(), lambda: 2.0, lambda: fired.append(clock.now()))
    timer.fire_if_over(3.0)
    assert fired == []


# -- TurnTaking -------------------------------------------------------------------------------------

# end_of_speech off: the pause alone ends the turn (END_OF_SPEECH turns it on)
CONFIG = SpeechEventConfig(speech_pause_period=1.5, speculation_gap=0.25, early_pause=0.0, end_of_speech=0.0)
EARLY = dataclasses.replace(CONFIG, early_pause=0.5)
NO_SPECULATION = dataclasses.replace(CONFIG, speculative_recognition=False)
END_OF_SPEECH = dataclasses.replace(CONFIG, speculation_gap=0.125, end_of_speech=0.375)


class Turn:
    """TurnTaking on a fake clock, with the times its pause ended and its gap passed."""

    def __init__(self, config: SpeechEventConfig) -> None:
        self.clock = FakeClock()
        self.lock = threading.Lock()
        self.ends: List[float] = []
        self.gaps: List[float] = []
        self.silences: List[float] = []
        self.gap_passed_at_gap: List[bool] = []
        self.held_lock: List[bool] = []
        self.turn = TurnTaking(
            config, self.clock, self.lock, self._ended, self._gap, self._silence, lambda *_: None
        )

    def _ended(self) -> None:
        self.ends.append(self.clock.now())
        self.held_lock.append(self.lock.locked())

    def _gap(self) -> None:
        self.gaps.append(self.clock.now())
        self.held_lock.append(self.lock.locked())
        self.gap_passed_at_gap.append(self.turn.gap_passed())

    def _silence(self) -> None:
        self.silences.append(self.clock.now())
        self.held_lock.append(self.lock.locked())

    def block(self, when: float) -> None:
        """A block arrives at ``when``."""
        self.clock.advance_to(when)
        self.turn.heard(when)

    def play(self, steps: Sequence[Tuple[float, str]]) -> None:
        """At each time, a block arrives or the node calls that method of TurnTaking (end_early ...)."""
        for when, what in steps:
            if what == "block":
                self.block(when)
            else:
                self.clock.advance_to(when)
                getattr(self.turn, what)()


@pytest.mark.parametrize(
    ("blocks", "before", "end"),
    [
        pytest.param([0.0], 1.25, 1.5, id="one_block_ends_the_utterance_speech_pause_period_after_it"),
        pytest.param([0.0, 0.5, 1.0, 1.25], 2.5, 2.75, id="after_the_last_of_several_blocks"),
    ],
)
def test_the_pause_ends_speech_pause_period_after_the_last_block(
    blocks: List[float], before: float, end: float
) -> None:
    turn = Turn(CONFIG)
    for when in blocks:
        turn.block(when)
    turn.clock.advance_to(before)
    assert turn.ends == []
    turn.clock.advance_to(10.0)
    assert turn.ends == [end]


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


class Run(NamedTuple):
    """What happens on the turn (see Turn.play); the times its pauses ended, its gaps passed and (with
    end_of_speech) its silences passed by 10 s."""

    config: SpeechEventConfig
    steps: List[Tuple[float, str]]
    ends: List[float]
    gaps: List[float]
    silences: Sequence[float] = ()


RUNS = {
    "each_utterance_has_its_own_pause": Run(
        CONFIG, [(0.0, "block"), (2.0, "block")], [1.5, 3.5], [0.25, 2.25]
    ),
    # the speculation, from the gap at 0.375, says a complete answer
    "a_complete_answer_ends_the_turn_early_pause_after_the_last_block": Run(
        EARLY, [(0.0, "block"), (0.125, "block"), (0.375, "end_early")], [0.625], [0.375]
    ),
    "with_early_pause_0_a_complete_answer_changes_nothing": Run(
        CONFIG, [(0.0, "block"), (0.25, "end_early")], [1.5], [0.25]
    ),
    "a_block_after_the_complete_answer_brings_back_the_whole_pause": Run(
        EARLY, [(0.0, "block"), (0.25, "end_early"), (0.375, "block")], [1.875], [0.25, 0.625]
    ),
    "the_utterance_after_an_early_end_waits_the_whole_pause": Run(
        EARLY, [(0.0, "block"), (0.25, "end_early"), (2.0, "block")], [0.5, 3.5], [0.25, 2.25]
    ),
    "the_gap_passes_once_per_pause": Run(CONFIG, [(0.0, "block"), (0.5, "block")], [2.0], [0.25, 0.75]),
    "without_speculative_recognition_the_gap_sets_no_timer": Run(NO_SPECULATION, [(0.0, "block")], [1.5], []),
    "drop_turn_waits_for_no_pause_and_leaves_the_gap_timer_set": Run(
        CONFIG, [(0.0, "block"), (0.0, "drop_turn")], [], [0.25]
    ),
    "the_next_block_after_drop_turn_starts_a_whole_pause": Run(
        CONFIG, [(0.0, "block"), (0.0, "drop_turn"), (1.0, "block")], [2.5], [0.25, 1.25]
    ),
    "stop_unsets_both_timers": Run(CONFIG, [(0.0, "block"), (0.0, "stop")], [], []),
    # the silence timer fired at 0.375 and was set again for 0.125 + 0.375
    "with_end_of_speech_the_gap_comes_first_and_the_silence_end_of_speech_after_the_last_block": Run(
        END_OF_SPEECH, [(0.0, "block"), (0.125, "block")], [1.625], [0.125, 0.25], [0.5]
    ),
    "a_gap_not_shorter_than_end_of_speech_sets_no_timer_of_its_own": Run(
        dataclasses.replace(END_OF_SPEECH, speculation_gap=0.375), [(0.0, "block")], [1.5], [], [0.375]
    ),
    "stop_unsets_the_silence_timer_too": Run(END_OF_SPEECH, [(0.0, "block"), (0.0, "stop")], [], [], []),
}


@pytest.mark.parametrize("run", list(RUNS.values()), ids=list(RUNS))
def test_the_pauses_that_end_and_the_gaps_that_pass(run: Run) -> None:
    turn = Turn(run.config)
    turn.play(run.steps)
    turn.clock.advance_to(10.0)
    assert turn.ends == run.ends
    assert turn.gaps == run.gaps
    assert turn.silences == list(run.silences)


def test_a_complete_answer_found_after_early_pause_ends_the_turn_at_once() -> None:
    turn = Turn(EARLY)
    turn.play([(0.0, "block"), (0.75, "end_early")])
    turn.clock.advance(0.0)
    assert turn.ends == [0.75]


def test_drop_turn_forgets_an_early_end() -> None:
    turn = Turn(EARLY)
    turn.play([(0.0, "block"), (0.25, "end_early"), (0.25, "drop_turn")])
    turn.clock.advance_to(1.0)
    assert turn.ends == []
    turn.block(2.0)
    turn.clock.advance_to(10.0)
    assert turn.ends == [3.5]


def test_the_gap_passes_speculation_gap_after_the_last_block() -> None:
    turn = Turn(CONFIG)
    turn.block(0.0)
    turn.block(0.125)
    turn.clock.advance_to(0.25)
    assert turn.gaps == []
    turn.clock.advance_to(1.0)
    assert turn.gaps == [0.375]
    assert turn.gap_passed_at_gap == [True]


@pytest.mark.parametrize(
    ("config", "blocks", "before", "at"),
    [
        # the first gap timer fired at 0.25 and was set again for 0.375
        pytest.param(CONFIG, [0.0, 0.125], 0.3125, 0.375, id="gap_passed_is_false_while_the_gap_timer_waits"),
        # no timer: the clock alone
        pytest.param(
            NO_SPECULATION, [0.0], 0.2489, 0.2491, id="gap_passed_comes_exactly_at_the_gap_less_the_tolerance"
        ),
    ],
)
def test_gap_passed_comes_at_the_gap(
    config: SpeechEventConfig, blocks: List[float], before: float, at: float
) -> None:
    turn = Turn(config)
    turn.play([(when, "block") for when in blocks])
    turn.clock.advance_to(before)
    assert not turn.turn.gap_passed()
    turn.clock.advance_to(at)
    assert turn.turn.gap_passed()


@pytest.mark.parametrize(
    ("config", "early", "now", "ends"),
    [
        pytest.param(CONFIG, False, 1.4375, [], id="before_the_pause_is_over_nothing_ends"),
        pytest.param(CONFIG, False, 1.5, [1.5], id="once_the_pause_is_over_the_utterance_ends"),
        pytest.param(EARLY, True, 0.5, [0.5], id="an_early_pause_over_ends_it_too"),
    ],
)
def test_a_block_after_the_pause_ends_the_utterance_although_the_timer_is_late(
    config: SpeechEventConfig, early: bool, now: float, ends: List[float]
) -> None:
    clock = ManualClock()  # no timer fires unless the test runs it: the timer thread is late
    turn_ends: List[float] = []
    turn = TurnTaking(
        config,
        clock,
        threading.Lock(),
        lambda: turn_ends.append(clock.now()),
        lambda: None,
        lambda: None,
        lambda *_: None,
    )
    turn.heard(0.0)
    if early:
        turn.end_early()
    clock.time = now
    turn.end_pause_if_over(now)
    assert turn_ends == ends


@pytest.mark.parametrize(
    ("now", "silences"),
    [
        pytest.param(0.3125, [], id="before_end_of_speech_without_a_block_nothing_is_heard"),
        pytest.param(0.375, [0.375], id="once_it_is_over_the_end_of_speech_is_heard_before_the_block"),
    ],
)
def test_a_block_after_end_of_speech_without_one_hears_the_end_although_the_timer_is_late(
    now: float, silences: List[float]
) -> None:
    clock = ManualClock()
    heard: List[float] = []
    turn = TurnTaking(
        END_OF_SPEECH,
        clock,
        threading.Lock(),
        lambda: None,
        lambda: None,
        lambda: heard.append(clock.now()),
        lambda *_: None,
    )
    turn.heard(0.0)
    clock.time = now
    turn.end_pause_if_over(now)
    assert heard == silences


def test_a_callback_that_returned_late_moves_the_end_of_speech_the_gap_and_the_pause_with_it() -> None:
    # The block at 0 was taken by a callback that returned at 0.33 (it waited for the lock): the
    # driver, which publishes in that thread, sends the next one at 0.40. No end of speech at 0.375
    # is heard: end_of_speech, the gap and the pause count from 0.33.
    turn = Turn(END_OF_SPEECH)
    turn.block(0.0)
    turn.turn.taken(0.33)
    turn.turn.end_pause_if_over(0.40)
    turn.block(0.40)
    assert turn.silences == []
    turn.clock.advance_to(10.0)
    assert turn.silences == [0.40 + 0.375]
    assert turn.ends == [0.40 + 1.5]


def test_a_callback_that_returned_late_delays_what_no_block_after_it_ends() -> None:
    turn = Turn(END_OF_SPEECH)
    turn.block(0.0)
    turn.turn.taken(0.25)
    turn.clock.advance_to(10.0)
    assert turn.gaps == [0.25 + 0.125]
    assert turn.silences == [0.25 + 0.375]
    assert turn.ends == [0.25 + 1.5]


def test_a_block_that_waits_for_the_lock_keeps_the_timers_from_hearing_a_pause_before_it() -> None:
    # The block at 0 was taken; the next arrived at 0.0625 and waited for the lock until 0.75 (the
    # worker held it, taking the blocks a decision had held). The timers due at 0.125 (the gap) and
    # 0.375 (end_of_speech) find it waiting and hear nothing; taken, it sets them again.
    turn = Turn(END_OF_SPEECH)
    turn.block(0.0)
    turn.turn.taken(0.0)
    with turn.turn.waiting_blocks.arriving(0.0625):
        turn.clock.advance_to(0.75)
        assert (turn.gaps, turn.silences, turn.ends) == ([], [], [])
        turn.turn.end_pause_if_over(0.0625)
        turn.turn.heard(0.0625)
        turn.turn.taken(0.75)
    turn.clock.advance_to(10.0)
    assert turn.gaps == [0.75 + 0.125]
    assert turn.silences == [0.75 + 0.375]
    assert turn.ends == [0.75 + 1.5]


def test_without_a_block_waiting_the_end_of_speech_is_heard_at_its_time() -> None:
    # the same, with the block not yet arrived: the pause before it is heard
    turn = Turn(END_OF_SPEECH)
    turn.block(0.0)
    turn.turn.taken(0.0)
    turn.clock.advance_to(0.75)
    assert (turn.gaps, turn.silences) == ([0.125], [0.375])


@pytest.mark.parametrize(
    ("arrival", "fired"),
    [
        pytest.param(1.9375, [], id="a_block_that_arrived_before_the_due_time_keeps_it_from_firing"),
        pytest.param(2.0, [2.0], id="one_that_arrived_once_it_was_due_does_not"),
    ],
)
def test_a_timer_due_while_a_block_waits_fires_only_if_it_was_due_before_the_block(
    arrival: float, fired: List[float]
) -> None:
    clock = ManualClock()
    heard: List[float] = []
    timer = RearmingTimer(
        clock, threading.Lock(), lambda: 2.0, lambda: heard.append(clock.now()), lambda: arrival
    )
    timer.arm()
    clock.time = 2.0
    clock.callbacks[0]()
    assert heard == fired
    assert not timer.armed


def test_arriving_blocks_are_waiting_until_taken_earliest_first() -> None:
    blocks = ArrivingBlocks()
    assert blocks.earliest() is None
    with blocks.arriving(2.0):
        with blocks.arriving(1.0):
            assert blocks.earliest() == 1.0
        assert blocks.earliest() == 2.0
    assert blocks.earliest() is None
    with pytest.raises(RuntimeError), blocks.arriving(3.0):
        raise RuntimeError("taking it failed")
    assert blocks.earliest() is None
