"""One walk over a timeline for every runner: in memory (harness/memory_runner.py) and on a real
roscore (harness/ros/runner.py).

The walk decides the order: it stops at each time at which an event happens, at each of the
runner's ``stops`` and at the timeline's end, moves the runner's clock there, then plays that
time's events in timeline order, letting the node settle before each and after the last. A client's
call that waits for a text (as the Behaviour Controller waits for the answer before it goes on) is
made once it has come: causality, not a margin of silence, orders it after the utterance. A runner
says only how its clock moves, how soundDetection does what the timeline says, and how the robot's
clients call the node.
"""

from collections import defaultdict
from typing import DefaultDict, Iterable, List, Protocol, Tuple, cast

from harness.timeline import CallService, ComeUp, Event, GoDown, Publish, SendGoal, Timeline
from speech_event.messages import Float32MultiArray, RecogniseSpeechGoal, message_type_name


class SoundDetection(Protocol):
    """soundDetection, and the other nodes that publish on its topic, as a runner plays them;
    ``index`` is the event's place in the timeline."""

    def publish(self, index: int, message: Float32MultiArray) -> None:
        """soundDetection publishes a block on its topic."""

    def intrude(self, index: int, message: object) -> None:
        """Another node publishes a message of another type on soundDetection's topic."""

    def go_down(self, crash: bool) -> None:
        """soundDetection shuts down, or crashes (leaving a stale registration)."""

    def come_up(self) -> None:
        """soundDetection is back, a publisher again."""


class Player(Protocol):
    """The rest of a runner: its clock, and the robot's clients of the node."""

    def advance_to(self, when: float) -> None:
        """Move the scenario clock on to ``when`` (never back)."""

    def settle(self, played: int, final: bool) -> None:
        """Let the node do what it does by now, ``played`` events in: before each event, and after
        the last one of a time (``final``: after the timeline's end)."""

    def call(self, service: str, request: object) -> None:
        """Call one of the node's services (the runner keeps the response)."""

    def send_goal(self, goal: RecogniseSpeechGoal) -> None:
        """Send the node an action goal (the runner keeps its result)."""

    def wait_for_text(self, played: int) -> None:
        """Before a call or goal that waits for the text of the utterance before it (``after =
        "text"``), ``played`` events in: in memory, check that the node has published a text since
        the last call or goal; on a real clock, wait for what it had published by then in memory
        (the events after it move later by the wait, as after a late answer)."""


def play(
    timeline: Timeline, player: Player, sound_detection: SoundDetection, stops: Iterable[float] = ()
) -> None:
    """Play every event of ``timeline``, stopping the clock also at each of ``stops``."""
    events_at: DefaultDict[float, List[Tuple[int, Event]]] = defaultdict(list)
    for index, event in enumerate(timeline.events):
        events_at[event.time].append((index, event))
    times = sorted({*events_at, *stops, timeline.end})
    played = 0
    for when in times:
        player.advance_to(when)
        for index, event in events_at.get(when, []):
            player.settle(played, final=False)
            if isinstance(event, (CallService, SendGoal)) and event.after_text:
                player.wait_for_text(played)
            _play_one(player, sound_detection, index, event)
            played = index + 1
        player.settle(played, final=when == times[-1])


def _play_one(player: Player, sound_detection: SoundDetection, index: int, event: Event) -> None:
    if isinstance(event, Publish):
        if message_type_name(event.message) == Float32MultiArray._type:
            sound_detection.publish(index, cast(Float32MultiArray, event.message))
        else:
            sound_detection.intrude(index, event.message)
    elif isinstance(event, GoDown):
        sound_detection.go_down(event.kind == "crash")
    elif isinstance(event, ComeUp):
        sound_detection.come_up()
    elif isinstance(event, CallService):
        player.call(event.service, event.request)
    elif isinstance(event, SendGoal):
        player.send_goal(event.goal)
