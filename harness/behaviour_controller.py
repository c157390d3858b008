"""The robot's Behaviour Controller's reading of /speechEvent/text, exactly as its C++ does
(cssr4africa ``cssr_system/behaviorController/src/behaviorControllerImplementation.cpp``,
``GetVisitorResponse``): what the robot concludes from the texts the node publishes.

It subscribes to the text topic and ticks once a second. At each tick it reads the latest text
received (an earlier one in the same second is overwritten unread): one that contains ``Error``
fails the step; otherwise the first of its affirmative words found anywhere in the text, with
``std::string::find`` (case-sensitive substrings: "go" is in "good", "no" in "know"), means yes,
then a negative word no. A text with neither concludes nothing, and after 10 s without a
conclusion it gives up ("No affirmative response received")."""

from typing import Dict, Sequence, Tuple

AFFIRMATIVE: Dict[str, Tuple[str, ...]] = {
    "english": ("yes", "great", "absolutely", "go", "happy", "good", "love"),
    "kinyarwanda": ("yego", "ntakibazo", "nibyo"),
}
NEGATIVE: Dict[str, Tuple[str, ...]] = {"english": ("no",), "kinyarwanda": ("oya",)}
YES, NO, NOTHING, FAILURE = "yes", "no", "", "failure"
GIVES_UP_AFTER = 10.0  # seconds


def conclusion(text: str, language: str = "english") -> str:
    """What one text read at a tick concludes: YES, NO, FAILURE, or NOTHING (it listens on)."""
    if "Error" in text:
        return FAILURE
    if any(word in text for word in AFFIRMATIVE[language]):
        return YES
    if any(word in text for word in NEGATIVE[language]):
        return NO
    return NOTHING


def visitor_response(
    published: Sequence[Tuple[float, str]], language: str = "english", asked_at: float = 0.0
) -> str:
    """What the step concludes from texts published at these times (seconds, in order), ticking
    from ``asked_at``: the latest text received by each tick is read at that tick, one published
    before the step too (the controller subscribes when its tree is built, not when it asks);
    after 10 s without a conclusion, NOTHING."""
    tick = 0
    read = 0  # texts received so far
    while True:
        now = asked_at + tick
        received = [text for when, text in published if when <= now]
        if len(received) > read:
            read = len(received)
            concluded = conclusion(received[-1], language)
            if concluded != NOTHING:
                return concluded
        if tick > GIVES_UP_AFTER:
            return NOTHING
        tick += 1
