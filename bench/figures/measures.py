"""What the figure benches share: the robot's commands they speak and judge against (one list, the
robot's grammar file), word errors against a reference, this process's memory, and how long an
engine keeps the other threads from running."""

from pathlib import Path
from typing import List, Tuple

from fixtures.recordings import word_errors as recorded_word_errors
from harness.cli import COMMANDS
from speech_event.grammar import load_grammar


def robot_commands() -> List[str]:
    """The robot's command phrases as the node reads its grammar file (harness/data/robot_commands.txt,
    the demo's grammar): the one list of commands every bench speaks and judges against."""
    return list(load_grammar(COMMANDS).sentences("a bench"))


def word_errors(reference: str, hypothesis: str) -> Tuple[int, int]:
    """(word edits, reference words) between two texts' words as they are written."""
    return recorded_word_errors(reference.split(), hypothesis.split())


def peak_mib() -> float:
    """This process's peak resident memory: VmHWM, which starts afresh at exec (ru_maxrss does not:
    it would carry the parent's peak, the quantizer's among it)."""
    return _status_mib("VmHWM")


def resident_mib() -> float:
    """This process's resident memory now (VmRSS)."""
    return _status_mib("VmRSS")


def _status_mib(field: str) -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(f"{field}:"):
            return int(line.split()[1]) / 1024
    raise RuntimeError(f"no {field} in /proc/self/status")
