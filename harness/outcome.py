"""What a replay observed: the texts the node published (final, partial, and their transcript
messages), its service responses, its action results."""

from dataclasses import dataclass, field
from typing import List

from speech_event.messages import TranscriptMessage

MEMORY, SIM_TIME, REAL_TIME = "memory", "sim time", "real time"


@dataclass(frozen=True)
class Published:
    time: float
    text: str
    # How many of the timeline's events had been played when it came (in memory): a ROS replay
    # waits for what came before the next event before it plays that event.
    played: int = 0


@dataclass
class Outcome:
    published: List[Published] = field(default_factory=list)
    responses: List[int] = field(default_factory=list)
    # One per action goal, in the order they ended, written by result_text.
    results: List[Published] = field(default_factory=list)
    # What came on /speechEvent/partial, and every /speechEvent/transcript message.
    partials: List[Published] = field(default_factory=list)
    transcripts: List[TranscriptMessage] = field(default_factory=list)
    # Whose clock the replay ran on: MEMORY (the fake clock: the times of partial texts and of
    # transcript messages are checked to the millisecond), SIM_TIME (ROS time driven by the
    # replay: their texts and order are), REAL_TIME (the wall clock: when a partial comes decides
    # what it has heard, so neither is compared; the final texts are).
    clock: str = MEMORY
    # In memory: each time one of the node's own timers fired (health checks, utterance ends by
    # whatever rule ended them, goal deadlines, ...). A ROS replay stops its clock at each.
    node_timers: List[float] = field(default_factory=list)
    # A ROS replay: each wait for what the node published in memory that ran out, saying how long
    # it waited and for what (a failing scenario's report shows them).
    gave_up: List[str] = field(default_factory=list)


def result_text(state: str, transcription: str) -> str:
    """A succeeded goal is its transcription; any other is its state in lower case, ': ' and it."""
    return transcription if state == "succeeded" else f"{state}: {transcription}"
