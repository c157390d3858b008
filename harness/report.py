"""One PASS/FAIL line per scenario; for a failure, a diff of expected versus observed."""

import difflib
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from harness.outcome import MEMORY, REAL_TIME, Outcome, Published
from harness.scenario import TRANSCRIPT_TIMES, Scenario
from speech_event import SOUND_DETECTION_DOWN
from speech_event.messages import TranscriptMessage


def _checks(scenario: Scenario, outcome: Outcome) -> List[Tuple[str, Sequence[str], Sequence[str]]]:
    """(what, expected, observed) for each thing the scenario asserts."""
    published = [message.text for message in outcome.published]
    checks: List[Tuple[str, Sequence[str], Sequence[str]]] = []
    if outcome.clock == REAL_TIME:
        # On the wall clock a recognition still running when a health check finds soundDetection
        # down is published after the error, where on a scenario clock it came before: the texts
        # in their order, and the errors in theirs (their times are in the report).
        for what, is_error in (("published texts", False), ("soundDetection errors", True)):
            checks.append(
                (
                    what,
                    [text for text in scenario.expected if (text == SOUND_DETECTION_DOWN) == is_error],
                    [text for text in published if (text == SOUND_DETECTION_DOWN) == is_error],
                )
            )
    else:
        checks.append(("published", scenario.expected, published))
    if scenario.expected_responses is not None:
        checks.append(
            ("responses", [str(r) for r in scenario.expected_responses], [str(r) for r in outcome.responses])
        )
    if scenario.expected_results is not None:
        checks.append(("results", scenario.expected_results, [result.text for result in outcome.results]))
    if scenario.expected_partials is not None and outcome.clock != REAL_TIME:
        timed = outcome.clock == MEMORY
        checks.append(
            (
                "partials",
                [_partial(partial.at, partial.text, timed) for partial in scenario.expected_partials],
                [_partial(partial.time, partial.text, timed) for partial in outcome.partials],
            )
        )
    if scenario.expected_transcripts is not None and outcome.clock != REAL_TIME:
        expected = [
            {
                key: value
                for key, value in fields.items()
                if outcome.clock == MEMORY or key not in TRANSCRIPT_TIMES
            }
            for fields in scenario.expected_transcripts
        ]
        observed = [_fields(message, fields.keys()) for message, fields in zip(outcome.transcripts, expected)]
        # Messages beyond those expected are shown with the required fields.
        observed += [_fields(message, ("text", "final")) for message in outcome.transcripts[len(expected) :]]
        checks.append(
            ("transcripts", [_written(fields) for fields in expected], [_written(f) for f in observed])
        )
    return checks


def _partial(time: float, text: str, timed: bool) -> str:
    """A partial text as its check compares it: with its time to the millisecond where ``timed``."""
    return f"t={time:.3f} s  {text!r}" if timed else repr(text)


def _fields(message: TranscriptMessage, keys: Iterable[str]) -> Dict[str, object]:
    """The fields of ``message`` named ``keys``."""
    return {key: getattr(message, key) for key in keys}


def _written(fields: Dict[str, object]) -> str:
    """One transcript message's fields as a check compares them: numbers to 3 places."""
    return ", ".join(
        f"{key}={value:.3f}"
        if isinstance(value, (int, float)) and not isinstance(value, bool)
        else f"{key}={value!r}"
        for key, value in fields.items()
    )


def passed(scenario: Scenario, outcome: Outcome) -> bool:
    """Every check holds, and a replay on a real clock never gave up waiting for what the node did
    by then in memory: one that did played on without it, and its outcome holding proves nothing
    about the order (listen_preempted's preempted result, waited for before the goal that causes it)."""
    checks_hold = all(
        list(expected) == list(observed) for _, expected, observed in _checks(scenario, outcome)
    )
    return checks_hold and not outcome.gave_up


def _timed(title: str, messages: Sequence[Published]) -> List[str]:
    return [f"      {title}, with scenario times:"] + [
        f"        t={message.time:8.3f} s  {message.text!r}" for message in messages
    ]


def report(scenario: Scenario, outcome: Outcome, hint: Optional[str] = None) -> str:
    """The PASS line, or the FAIL line with diffs, times, and ``hint`` (what may explain it)."""
    if passed(scenario, outcome):
        return f"PASS  {scenario.name}  ({scenario.source}, {len(outcome.published)} messages)"
    lines: List[str] = [f"FAIL  {scenario.name}  ({scenario.source})"]
    for what, expected, observed in _checks(scenario, outcome):
        if list(expected) == list(observed):
            continue
        label: Optional[str] = None if what == "published" else what
        diff = difflib.unified_diff(
            list(expected),
            list(observed),
            f"expected {label}" if label else "expected",
            label or "published",
            lineterm="",
            n=len(observed) + 1,
        )
        lines.extend("      " + line for line in diff)
    lines.extend(_timed("published", outcome.published))
    if outcome.results:
        lines.extend(_timed("action results", outcome.results))
    for wait in outcome.gave_up:
        first, *more = wait.splitlines()
        lines.append(f"      gave up: {first}")
        lines.extend(f"        {line}" for line in more)
    if hint:
        lines.append(f"      note: {hint}")
    return "\n".join(lines)
