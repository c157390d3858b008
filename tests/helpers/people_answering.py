"""People answering the robot's question in free speech, as its Behaviour Controller listens: Speech
Commands clips of "yes", "no" and "go" (tests/recordings/speech_commands, none of the held-out
test files) played one after another to the node with the robot's configuration (no grammar), and
what the controller concludes from each text (harness/behaviour_controller.py)."""

from dataclasses import dataclass
from typing import Any, Dict, List

from harness.behaviour_controller import conclusion
from harness.memory_runner import run_in_memory
from harness.scenario import parse_scenario
from speech_event.config import SpeechEventConfig
from tests.helpers.paths import ROOT

CLIPS = ROOT / "tests" / "recordings" / "speech_commands"
ANSWERS = ("yes", "no", "go")  # "go" is one of the controller's affirmative words
CLIPS_A_WORD = 4  # the first four speakers of each word (by file name): a minute of speech in all


@dataclass(frozen=True)
class Heard:
    said: str  # the word the clip says
    text: str  # what the node published
    written: str  # the engine's own writing (the transcript message)
    concluded: str  # what the controller concludes from the text


def answers_heard(recognizer: str) -> List[Heard]:
    """Each clip of ANSWERS through the node on ``recognizer``, 2 s of silence after each."""
    said = [(word, path) for word in ANSWERS for path in sorted((CLIPS / word).glob("*.wav"))[:CLIPS_A_WORD]]
    steps: List[Dict[str, Any]] = []
    for _, path in said:
        steps += [{"play": str(path)}, {"silence": 2.0}]
    document = {"name": "answers", "recognizer": recognizer, "steps": steps, "expect": {"published": []}}
    outcome = run_in_memory(parse_scenario(document, str(ROOT / "answers.toml"), SpeechEventConfig()))
    texts = [message.text for message in outcome.published]
    written = [message.text for message in outcome.transcripts if message.final]
    assert len(texts) == len(written) == len(said), texts  # one text a clip
    return [
        Heard(word, text, engine, conclusion(text)) for (word, _), text, engine in zip(said, texts, written)
    ]
