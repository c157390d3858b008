"""Counts rejected and clipped messages and logs each kind at a bounded rate.

A flood of bad messages (a misconfigured publisher sends dozens a second) must neither fill the
log nor hide how many there were: the first of each kind is logged at once, later ones at most
once per ``interval`` with the number held back since.
"""

import logging
from typing import Callable, Dict

from speech_event.pipeline.validate import CLIP_LIMIT, Reason, Rejection

_LOG = logging.getLogger("speech_event")
_CLIPPED = "clipped"


class RejectionLog:
    """Counts rejected and clipped messages on ``topic``; warns of each kind at most once per ``interval``."""

    def __init__(self, now: Callable[[], float], topic: str, interval: float = 10.0) -> None:
        self._now = now
        self._topic = topic
        self._interval = interval
        self.counts: Dict[Reason, int] = {reason: 0 for reason in Reason}
        # Accepted messages with samples a hair outside [-1, 1], clipped: counted apart.
        self.clipped = 0
        self._last_logged: Dict[str, float] = {}
        self._held_back: Dict[str, int] = {}

    def record(self, rejection: Rejection) -> None:
        self.counts[rejection.reason] += 1
        self._warn(rejection.reason.value, f"rejected a message on {self._topic}: {rejection.detail}")

    def record_clipped(self, samples: int) -> None:
        self.clipped += 1
        self._warn(
            _CLIPPED,
            f"clipped {samples} samples outside [-1, 1] in a message on {self._topic} "
            f"(peaks below {CLIP_LIMIT:g} are clipped: int16 / 32767 and resampling overshoot a little)",
        )

    def _warn(self, kind: str, text: str) -> None:
        now = self._now()
        last = self._last_logged.get(kind)
        if last is not None and now - last < self._interval:
            self._held_back[kind] = self._held_back.get(kind, 0) + 1
            return
        held_back = self._held_back.pop(kind, 0)
        suffix = f" ({held_back} more like it since the last warning)" if held_back else ""
        _LOG.warning("%s%s", text, suffix)
        self._last_logged[kind] = now
