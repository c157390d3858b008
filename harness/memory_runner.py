"""Plays a scenario to the node on the in-memory bus with a fake clock: no sleeping, deterministic."""

from typing import Optional

from harness.catalog import engine_builder_for, recognizer_for
from harness.outcome import Outcome, Published, result_text
from harness.scenario import Scenario
from harness.timeline import CallService, ComeUp, GoDown, Publish, SendGoal, build_timeline
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus, MemoryGoal
from speech_event.interfaces.action import ACTION_NAME
from speech_event.messages import Float32MultiArray, String, message_type_name
from speech_event.node import SpeechEventNode

SOUND_DETECTION = "soundDetection"


def run_in_memory(
    scenario: Scenario,
    recognition_seconds: float = 0.0,
    bus: Optional[InMemoryBus] = None,
    clock: Optional[FakeClock] = None,
) -> Outcome:
    """Every message the node published on /speechEvent/text, with its scenario time, every service
    response and every action result.

    ``recognition_seconds`` is how much scenario time each recognition takes. ``bus`` and ``clock``:
    ones that others watch too (the demo's window).
    """
    timeline = build_timeline(scenario)
    clock = clock or FakeClock()
    bus = bus or InMemoryBus()
    outcome = Outcome()
    played = 0
    bus.subscribe(
        TEXT_TOPIC,
        String,
        lambda message: outcome.published.append(
            Published(clock.now(), message.data, played)  # type: ignore[attr-defined]
        ),
    )

    def goal_ended(goal: MemoryGoal) -> None:
        transcription = getattr(goal.result, "transcription", "")
        outcome.results.append(Published(clock.now(), result_text(goal.state, transcription), played))

    bus.on_goal_end(goal_ended)
    executor = ClockExecutor(clock, recognition_seconds)
    node = SpeechEventNode(
        scenario.config,
        bus,
        clock,
        recognizer_for(scenario.recognizer, scenario.config),
        executor,
        engine_builder_for(scenario.recognizer, scenario.config),
    )
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node=SOUND_DETECTION)
    node.start()
    for event in timeline.events:
        clock.advance_to(event.time)
        if isinstance(event, Publish):
            if message_type_name(event.message) == Float32MultiArray._type:
                sound_detection.publish(event.message)
            else:  # another node, publishing another type on the same topic
                intruder = bus.advertise(SIGNAL_TOPIC, type(event.message), node="wrongTypePublisher")
                intruder.publish(event.message)
                intruder.shutdown()
        elif isinstance(event, GoDown):
            if event.kind == "crash":
                sound_detection.crash()
            else:
                sound_detection.shutdown()
        elif isinstance(event, ComeUp):
            sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node=SOUND_DETECTION)
        elif isinstance(event, CallService):
            outcome.responses.append(int(bus.call(event.service, event.request).response))  # type: ignore[attr-defined]
        elif isinstance(event, SendGoal):
            bus.send_goal(ACTION_NAME, event.goal)
        played += 1
    clock.advance_to(timeline.end)
    clock.advance_to(max(timeline.end, executor.free_at))  # recognitions still running finish
    node.stop()
    node.flush_storage()
    return outcome
