"""One PASS/FAIL line per scenario; for a failure, a diff of expected versus observed."""

import difflib
from typing import List, Optional, Sequence, Tuple

from harness.outcome import Outcome, Published
from harness.scenario import Scenario


def _checks(scenario: Scenario, outcome: Outcome) -> List[Tuple[str, Sequence[str], Sequence[str]]]:
    """(what, expected, observed) for each thing the scenario asserts."""
    checks: List[Tuple[str, Sequence[str], Sequence[str]]] = [
        ("published", scenario.expected, [message.text for message in outcome.published])
    ]
    if scenario.expected_responses is not None:
        checks.append(
            ("responses", [str(r) for r in scenario.expected_responses], [str(r) for r in outcome.responses])
        )
    if scenario.expected_results is not None:
        checks.append(("results", scenario.expected_results, [result.text for result in outcome.results]))
    return checks


def passed(scenario: Scenario, outcome: Outcome) -> bool:
    return all(list(expected) == list(observed) for _, expected, observed in _checks(scenario, outcome))


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
    if hint:
        lines.append(f"      note: {hint}")
    return "\n".join(lines)
