"""Plays a scenario to our node on the in-memory bus in real time: the wall clock (each of the
node's timers a thread), the recognition worker thread, partial results and speculation as on the
robot. What it publishes must be what it publishes on the fake clock, however busy the machine
(issue 30); ``python -m harness run --real-time`` without ``--transport ros``.

The waits are the ROS real-time replay's (harness/schedule.py): the scenario's t = 0 comes just
after one of the node's health checks, so its checks fall where they do on the scenario clock;
the events are played at their times, those after a call answered late moved later with it
(ScenarioWallClock); at the end the runner waits for every text and action
result the node published by then in memory, until a deadline, and says how long it waited for
what did not come.
"""

import dataclasses
from typing import Optional

from harness.catalog import ScenarioEngines
from harness.memory_runner import SoundDetectionOnTheBus
from harness.outcome import REAL_TIME, Outcome, Published, result_text
from harness.player import play
from harness.scenario import Scenario
from harness.schedule import (
    IN_MEMORY_ALIGN_MARGIN,
    TEXT_DEADLINE,
    ScenarioWallClock,
    Schedule,
    block_just_played,
)
from harness.timeline import Timeline, build_timeline
from speech_event import TEXT_TOPIC
from speech_event.adapters.executors import ThreadExecutor
from speech_event.adapters.memory_bus import InMemoryBus, MemoryGoal
from speech_event.adapters.system_clock import SystemClock
from speech_event.interfaces.action import ACTION_NAME
from speech_event.messages import RecogniseSpeechGoal, String
from speech_event.node import SpeechEventNode

# How long the node's worker may take to finish its queued recognitions once the scenario is over.
WORKER_STOP_TIMEOUT = 30.0


class _RealTime:
    """The scenario clock is the wall clock from t = 0 on; what the node publishes is collected."""

    def __init__(
        self, bus: InMemoryBus, schedule: Schedule, text_deadline: float, timeline: Timeline, pause: float
    ) -> None:
        self.bus = bus
        self._schedule = schedule
        self._events = timeline.events
        self._pause = pause
        self._goals_sent = 0
        self._text_deadline = text_deadline
        self.outcome = Outcome(clock=REAL_TIME)
        self._clock = ScenarioWallClock()
        self._now = 0.0
        bus.subscribe(TEXT_TOPIC, String, self._on_text)
        bus.on_goal_end(self._on_goal_end)

    def _scenario_time(self) -> float:
        return self._clock.now()

    def _on_text(self, message: object) -> None:
        text = message.data  # type: ignore[attr-defined]
        self.outcome.published.append(Published(self._scenario_time(), text))

    def _on_goal_end(self, goal: MemoryGoal) -> None:
        transcription = getattr(goal.result, "transcription", "")
        self.outcome.results.append(Published(self._scenario_time(), result_text(goal.state, transcription)))

    def begin(self, node_started: float, period: float) -> None:
        """Start the scenario clock just after the node's start, or where that has passed, one of
        its health checks (``node_started``: when its checks count from, on the wall clock); waits
        for it."""
        self._clock.start(node_started, period, IN_MEMORY_ALIGN_MARGIN)
        self.outcome = Outcome(clock=REAL_TIME)  # what the node said before t = 0 is no part of it

    def advance_to(self, when: float) -> None:
        self._now = when
        self._clock.sleep_until(when)

    def settle(self, played: int, final: bool) -> None:
        """Only at the end: waiting before an event would shift the events after it. After a block
        that went out late before a silence, the events after it move later (played_late)."""
        if final:
            self._wait_for_due(played)
            return
        block = block_just_played(self._events, played, self._now)
        if block is not None and self._goals_sent == len(self.outcome.results):  # no goal waits
            self._clock.played_late(*block, self._pause)

    def wait_for_text(self, played: int) -> None:
        """The call waits; the call's answer then moves the events after it (ScenarioWallClock)."""
        self._wait_for_due(played)

    def _wait_for_due(self, played: int) -> None:
        # partial texts are not collected: when one comes decides what it has heard
        due = dataclasses.replace(self._schedule.due(self._now, played), partials=())
        gave_up = due.wait(self.outcome, self._text_deadline, self._scenario_time)
        if gave_up:
            self.outcome.gave_up.append(gave_up)

    def call(self, service: str, request: object) -> None:
        self.outcome.responses.append(int(self.bus.call(service, request).response))  # type: ignore[attr-defined]
        self._clock.answered(self._now)

    def send_goal(self, goal: RecogniseSpeechGoal) -> None:
        self._goals_sent += 1
        self.bus.send_goal(ACTION_NAME, goal)
        self._clock.answered(self._now)


def run_in_real_time(scenario: Scenario, text_deadline: Optional[float] = None) -> Outcome:
    """What our node published on /speechEvent/text, its service responses and its action results,
    with their times on the scenario clock; partial texts are not collected (when one comes
    decides what it has heard)."""
    timeline = build_timeline(scenario)
    bus = InMemoryBus()
    deadline = TEXT_DEADLINE if text_deadline is None else text_deadline
    runner = _RealTime(bus, Schedule.of(scenario), deadline, timeline, scenario.config.speech_pause_period)
    sound_detection = SoundDetectionOnTheBus(bus)
    clock, executor = SystemClock(), ThreadExecutor()
    with ScenarioEngines(scenario.recognizer, scenario.config) as engines:
        node = SpeechEventNode(scenario.config, bus, clock, engines.build(), executor, engines.build)
        node.start()
        try:
            runner.begin(node.started_at, scenario.config.health_check_period)
            play(timeline, runner, sound_detection)
        finally:
            outcome = runner.outcome
            node.stop()
            executor.shutdown(WORKER_STOP_TIMEOUT)
    return outcome
