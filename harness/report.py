"""One PASS/FAIL line per scenario; for a failure, a diff of expected versus published."""

import difflib
from typing import List, Sequence

from harness.memory_runner import Published
from harness.scenario import Scenario


def passed(scenario: Scenario, published: Sequence[Published]) -> bool:
    return [message.text for message in published] == list(scenario.expected)


def report(scenario: Scenario, published: Sequence[Published]) -> str:
    texts = [message.text for message in published]
    if texts == list(scenario.expected):
        return f"PASS  {scenario.name}  ({scenario.source}, {len(texts)} messages)"
    lines: List[str] = [f"FAIL  {scenario.name}  ({scenario.source})"]
    diff = difflib.unified_diff(
        list(scenario.expected), texts, "expected", "published", lineterm="", n=len(texts) + 1
    )
    lines.extend("      " + line for line in diff)
    lines.append("      published, with scenario times:")
    lines.extend(f"        t={message.time:8.3f} s  {message.text!r}" for message in published)
    return "\n".join(lines)
