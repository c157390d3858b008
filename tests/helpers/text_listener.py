"""A subscriber to /speechEvent/text in a process of its own (on any host), and what it heard.

It writes each text with the wall-clock time it arrived, so a test can tell whether errors came
at their check times or in a burst afterwards.
"""

from pathlib import Path
from typing import List, Sequence, Tuple

from speech_event import SOUND_DETECTION_DOWN

LISTENER = """
import sys, time
import rospy
from std_msgs.msg import String
rospy.init_node("listener", disable_signals=True)
rospy.Subscriber("/speechEvent/text", String, lambda m: print(f"{time.time():.3f} {m.data}", flush=True))
rospy.spin()
"""


def write_listener(folder: Path) -> Path:
    script = folder / "listener.py"
    script.write_text(LISTENER)
    return script


def received(log: Path) -> List[Tuple[float, str]]:
    """(arrival time, text) for each text the listener has written to ``log`` so far."""
    lines = log.read_text().splitlines() if log.exists() else []
    return [(float(line.split(" ", 1)[0]), line.split(" ", 1)[1]) for line in lines if line[:1].isdigit()]


def assert_errors_on_time(
    heard: Sequence[Tuple[float, str]], start: float, end: float, period: float
) -> None:
    """Between ``start`` and ``end`` (the master unreachable) an error came at every check, none
    held back for a burst at ``end``."""
    assert all(text == SOUND_DETECTION_DOWN for _, text in heard), heard
    during = [at for at, _ in heard if start < at <= end]
    assert len(during) >= (end - start) / period - 2, heard
    assert max(later - earlier for earlier, later in zip([start, *during], [*during, end])) < 2 * period, (
        heard
    )
    assert len([at for at, _ in heard if end < at <= end + 0.5]) <= 1, heard
