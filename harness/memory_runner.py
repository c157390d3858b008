"""Plays a scenario to the node on the in-memory bus with a fake clock: no sleeping, deterministic
(harness/real_time_runner.py plays it there on the wall clock)."""

import contextlib
from typing import Callable, List, Optional

from harness.catalog import ScenarioEngines
from harness.outcome import Outcome, Published, result_text
from harness.player import play
from harness.scenario import Scenario, ScenarioError
from harness.timeline import build_timeline
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus, MemoryGoal, MemoryPublisher
from speech_event.interfaces.action import ACTION_NAME
from speech_event.messages import Float32MultiArray, RecogniseSpeechGoal, String, TranscriptMessage
from speech_event.node import SpeechEventNode
from speech_event.ports import Timer
from speech_event.topics import PARTIAL_TOPIC, SOUND_DETECTION_DOWN, TRANSCRIPT_TOPIC

SOUND_DETECTION = "soundDetection"
# The most scenario time a call waits for a text when recognition takes time (run_in_memory's
# recognition_seconds): a minute of an engine's work and more.
LONGEST_TEXT_WAIT = 60.0


class _NodeClock:
    """The fake clock as the node sees it, noting when each of the node's own timers fires."""

    def __init__(self, clock: FakeClock, fired: List[float]) -> None:
        self._clock = clock
        self._fired = fired

    def now(self) -> float:
        return self._clock.now()

    def call_at(self, when: float, callback: Callable[[], None]) -> Timer:
        def fire() -> None:
            self._fired.append(self._clock.now())
            callback()

        return self._clock.call_at(when, fire)


class SoundDetectionOnTheBus:
    """soundDetection on the in-memory bus: a publisher there, shut down, crashed and back."""

    def __init__(self, bus: InMemoryBus) -> None:
        self._bus = bus
        self._publisher = self._advertise()

    def _advertise(self) -> MemoryPublisher:
        return self._bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node=SOUND_DETECTION)

    def publish(self, index: int, message: Float32MultiArray) -> None:
        self._publisher.publish(message)

    def intrude(self, index: int, message: object) -> None:
        intruder = self._bus.advertise(SIGNAL_TOPIC, type(message), node="wrongTypePublisher")
        intruder.publish(message)
        intruder.shutdown()

    def go_down(self, crash: bool) -> None:
        if crash:
            self._publisher.crash()
        else:
            self._publisher.shutdown()

    def come_up(self) -> None:
        self._publisher = self._advertise()


class _InMemory:
    """The scenario's time is the fake clock's; the robot's clients call the node on the bus, and
    what the node publishes there is collected."""

    def __init__(self, bus: InMemoryBus, clock: FakeClock, recognition_seconds: float) -> None:
        self.bus = bus
        self._clock = clock
        self._instant = recognition_seconds == 0.0
        # How long calls waited for a text: the events after them come that much later.
        self._waited = 0.0
        self.outcome = Outcome()
        self._played = 0
        self._texts_at_last_call = 0  # utterances' texts published before the last call or goal
        bus.subscribe(TEXT_TOPIC, String, self._on_text)
        bus.subscribe(PARTIAL_TOPIC, String, self._on_partial)
        bus.subscribe(TRANSCRIPT_TOPIC, TranscriptMessage, self._on_transcript)
        bus.on_goal_end(self._on_goal_end)

    def _on_text(self, message: object) -> None:
        text = message.data  # type: ignore[attr-defined]
        self.outcome.published.append(Published(self._clock.now(), text, self._played))

    def _on_partial(self, message: object) -> None:
        text = message.data  # type: ignore[attr-defined]
        self.outcome.partials.append(Published(self._clock.now(), text, self._played))

    def _on_transcript(self, message: object) -> None:
        assert isinstance(message, TranscriptMessage)
        self.outcome.transcripts.append(message)

    def _on_goal_end(self, goal: MemoryGoal) -> None:
        transcription = getattr(goal.result, "transcription", "")
        text = result_text(goal.state, transcription)
        self.outcome.results.append(Published(self._clock.now(), text, self._played))

    def advance_to(self, when: float) -> None:
        self._clock.advance_to(when + self._waited)

    def settle(self, played: int, final: bool) -> None:
        self._played = played
        self._clock.advance_to(self._clock.now())  # the timers set at this time by the last event

    def call(self, service: str, request: object) -> None:
        self._after_event()
        self._texts_at_last_call = self._texts()
        self.outcome.responses.append(int(self.bus.call(service, request).response))  # type: ignore[attr-defined]

    def send_goal(self, goal: RecogniseSpeechGoal) -> None:
        self._after_event()
        self._texts_at_last_call = self._texts()
        self.bus.send_goal(ACTION_NAME, goal)

    def _after_event(self) -> None:
        """What the node does in its answer to a call or goal (a newer goal's preempting the one
        before) comes after that event: a ROS replay must not wait for it before playing the event
        (it waited its whole text deadline, 30 s, for the preempted result of
        scenarios/listen_preempted.toml, then went on). The walk settled just before the event."""
        self._played += 1

    def wait_for_text(self, played: int) -> None:
        """The clock moves on, timer by timer, until a text has come since the last call or goal.
        Where recognition takes no time (the scenario as written, and the rehearsal a replay on a
        real clock follows) it must have come by the call's time."""
        asked_at = self._clock.now()
        while self._texts() == self._texts_at_last_call:
            due = self._clock.next_due()
            if self._instant or due is None or due > asked_at + LONGEST_TEXT_WAIT:
                raise ScenarioError(
                    f"the call at t={asked_at:.3f} s waits for the text of the utterance before it "
                    '(after = "text"), but the node published none by then since the last call or '
                    'goal; after = "text" is allowed only where that text comes before the call'
                )
            self._clock.advance_to(due)
        self._waited += self._clock.now() - asked_at

    def _texts(self) -> int:
        return sum(item.text != SOUND_DETECTION_DOWN for item in self.outcome.published)


def run_in_memory(
    scenario: Scenario,
    recognition_seconds: float = 0.0,
    bus: Optional[InMemoryBus] = None,
    clock: Optional[FakeClock] = None,
    engines: Optional[ScenarioEngines] = None,
) -> Outcome:
    """Every message the node published on /speechEvent/text, with its scenario time, every service
    response and every action result; and when the node's own timers fired (``node_timers``).

    ``recognition_seconds`` is how much scenario time each recognition takes. ``bus`` and ``clock``:
    ones that others watch too (the demo's window). ``engines``: built for the scenario's
    recognizer already (simulated), and kept after the run (harness/catalog.py says when runs may
    share them); by default the run's own.
    """
    timeline = build_timeline(scenario)
    clock = clock or FakeClock()
    runner = _InMemory(bus or InMemoryBus(), clock, recognition_seconds)
    sound_detection = SoundDetectionOnTheBus(runner.bus)
    node_clock = _NodeClock(clock, runner.outcome.node_timers)
    executor = ClockExecutor(node_clock, recognition_seconds)
    with contextlib.ExitStack() as stack:
        if engines is None:
            engines = stack.enter_context(
                ScenarioEngines(scenario.recognizer, scenario.config, simulated=True)
            )
        node = SpeechEventNode(
            scenario.config, runner.bus, node_clock, engines.build(), executor, engines.build
        )
        node.start()
        play(timeline, runner, sound_detection)
        clock.advance_to(max(clock.now(), executor.free_at))  # recognitions still running finish
        node.stop()
        node.flush_storage()
    return runner.outcome
