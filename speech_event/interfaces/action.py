"""The ``recognise_speech`` action of the robot's release v1.1: listen for one utterance.

A goal (``wait`` seconds) listens from the moment it is accepted. Its result is the text the node
publishes for the first utterance that starts after that moment ("" when it publishes nothing for
it); utterances thrown away as not speech (too short, below ``vad_threshold``) do not count. With
no speech started within ``wait`` seconds it succeeds with "". It is aborted when the node is
disabled or soundDetection is down, at arrival or while it still waits for its utterance to end; a
newer goal preempts it, and a cancel request ends it as preempted. Progress feedback: 0 when
accepted, 10 more at each tenth of ``wait`` until speech starts, 100 just before a success.

The node tells it what happens to utterances; it keeps its own state under its own lock and calls
the goal handles only outside that lock, so it never holds a lock that a transport's goal callback
(actionlib calls back under its server lock) could be waiting for.
"""

import functools
import math
import threading
from dataclasses import dataclass, field
from typing import Callable, List, Optional

from speech_event.messages import RecogniseSpeechFeedback, RecogniseSpeechResult
from speech_event.ports import TIMER_TOLERANCE, ActionGoal, Clock, Timer
from speech_event.topics import SOUND_DETECTION_DOWN

ACTION_NAME = "/speechEvent/recognise_speech_action"
DISABLED = "Error: speechEvent is disabled"
PROGRESS_STEPS = 10


@dataclass
class _Goal:
    handle: ActionGoal
    accepted_at: float
    deadline: float
    # Closed utterances that started after the goal was accepted, by number, oldest first.
    candidates: List[int] = field(default_factory=list)
    timers: List[Timer] = field(default_factory=list)
    progress: int = 0


class ListenAction:
    """Serves the recognise_speech action: one goal at a time, answered with the next utterance's text."""

    def __init__(self, clock: Clock, refusal: Callable[[], Optional[str]]) -> None:
        """``refusal`` says why a goal cannot listen now (the text to abort with), or None."""
        self._clock = clock
        self._refusal = refusal
        self._lock = threading.Lock()
        self._goal: Optional[_Goal] = None
        # When the utterance being collected started; None when none is being collected.
        self._collecting_since: Optional[float] = None

    # -- the transport's callbacks ------------------------------------------------------------------

    def on_goal(self, handle: ActionGoal) -> None:
        wait = float(getattr(handle.goal, "wait", float("nan")))
        refusal = self._refusal()
        if not math.isfinite(wait) or wait < 0:
            refusal = f"Error: wait = {wait} is not allowed; allowed: a number of seconds, 0 or more"
        now = self._clock.now()
        with self._lock:
            previous, self._goal = self._goal, None
            goal = _Goal(handle, now, now + wait)
            if refusal is None:
                self._goal = goal
        if previous is not None:
            self._end(previous, "cancel", "")
        handle.accept()
        if refusal is not None:
            handle.abort(RecogniseSpeechResult(refusal))
        else:
            handle.feedback(RecogniseSpeechFeedback(0))
            self._arm(goal, wait)

    def on_cancel(self, handle: ActionGoal) -> None:
        with self._lock:
            goal = self._take(lambda goal: goal.handle is handle)
        if goal is not None:
            self._end(goal, "cancel", "")

    # -- what the node tells it ---------------------------------------------------------------------

    def utterance_started(self, when: float) -> None:
        """Called under the node's lock: it only records."""
        with self._lock:
            self._collecting_since = when

    def utterance_closed(self, number: int, started_at: float, more_follows: bool) -> None:
        """Called under the node's lock when utterance ``number`` goes to recognition.

        ``more_follows``: it was cut at the length limit and the speech goes on (same start).
        """
        with self._lock:
            self._collecting_since = started_at if more_follows else None
            if self._goal is not None and started_at > self._goal.accepted_at:
                self._goal.candidates.append(number)

    def utterance_dropped(self) -> None:
        """The utterance being collected was thrown away (the node was disabled)."""
        with self._lock:
            self._collecting_since = None

    def utterance_done(self, number: int, text: Optional[str]) -> None:
        """Recognition of ``number`` ended: the text published for it, "" for none, None if it was
        thrown away as not speech."""
        with self._lock:
            goal = self._goal
            if goal is None or not goal.candidates or goal.candidates[0] != number:
                return
            goal.candidates.pop(0)
            if text is None and (goal.candidates or not self._timed_out(goal)):
                return  # not speech: listen on
            self._goal = None
        self._end(goal, "succeed", text or "")

    def refuse_waiting(self, reason: str) -> None:
        """Abort a goal still waiting for its utterance (disabled, soundDetection down)."""
        with self._lock:
            goal = self._take(lambda goal: not goal.candidates)
        if goal is not None:
            self._end(goal, "abort", reason)

    def sound_detection_down(self) -> None:
        self.refuse_waiting(SOUND_DETECTION_DOWN)

    def disabled(self) -> None:
        self.refuse_waiting(DISABLED)

    # -- inside ---------------------------------------------------------------------------------------

    def _take(self, condition: Callable[[_Goal], bool]) -> Optional[_Goal]:
        goal = self._goal
        if goal is None or not condition(goal):
            return None
        self._goal = None
        return goal

    def _timed_out(self, goal: _Goal) -> bool:
        """No speech that started after acceptance is being heard, and the wait is over (the
        deadline's timer may fire a little early: without the tolerance such a goal never ended)."""
        started = self._collecting_since is not None and self._collecting_since > goal.accepted_at
        return not started and self._clock.now() >= goal.deadline - TIMER_TOLERANCE

    def _arm(self, goal: _Goal, wait: float) -> None:
        for step in range(1, PROGRESS_STEPS):
            when = goal.accepted_at + wait * step / PROGRESS_STEPS
            goal.timers.append(self._clock.call_at(when, functools.partial(self._tick, goal, step)))
        goal.timers.append(self._clock.call_at(goal.deadline, lambda: self._on_deadline(goal)))

    def _tick(self, goal: _Goal, step: int) -> None:
        with self._lock:
            hearing = self._collecting_since is not None and self._collecting_since > goal.accepted_at
            if self._goal is not goal or hearing or goal.candidates:
                return
            goal.progress = step * 100 // PROGRESS_STEPS
        goal.handle.feedback(RecogniseSpeechFeedback(goal.progress))

    def _on_deadline(self, goal: _Goal) -> None:
        with self._lock:
            if self._goal is not goal or goal.candidates or not self._timed_out(goal):
                return
            self._goal = None
        self._end(goal, "succeed", "")

    @staticmethod
    def _end(goal: _Goal, outcome: str, transcription: str) -> None:
        """Finish a goal already taken out of ``_goal``; never called under the lock."""
        for timer in goal.timers:
            timer.cancel()
        result = RecogniseSpeechResult(transcription)
        if outcome == "succeed":
            goal.handle.feedback(RecogniseSpeechFeedback(100))
            goal.handle.succeed(result)
        elif outcome == "abort":
            goal.handle.abort(result)
        else:
            goal.handle.cancel(result)
