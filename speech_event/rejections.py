"""Counts rejected messages per reason and logs each reason at a bounded rate.

A flood of bad messages (a misconfigured publisher sends dozens a second) must neither fill the
log nor hide how many there were: the first of each reason is logged at once, later ones at most
once per ``interval`` with the number held back since.
"""

import logging
from typing import Callable, Dict

from speech_event.validate import Reason, Rejection

_LOG = logging.getLogger("speech_event")


class RejectionLog:
    def __init__(self, now: Callable[[], float], topic: str, interval: float = 10.0) -> None:
        self._now = now
        self._topic = topic
        self._interval = interval
        self.counts: Dict[Reason, int] = {reason: 0 for reason in Reason}
        self._last_logged: Dict[Reason, float] = {}
        self._held_back: Dict[Reason, int] = {reason: 0 for reason in Reason}

    def record(self, rejection: Rejection) -> None:
        reason = rejection.reason
        self.counts[reason] += 1
        now = self._now()
        last = self._last_logged.get(reason)
        if last is not None and now - last < self._interval:
            self._held_back[reason] += 1
            return
        held_back = self._held_back[reason]
        suffix = f" ({held_back} more like it since the last warning)" if held_back else ""
        _LOG.warning("rejected a message on %s: %s%s", self._topic, rejection.detail, suffix)
        self._last_logged[reason] = now
        self._held_back[reason] = 0
