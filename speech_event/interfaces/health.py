"""Health: soundDetection checked every health_check_period, /diagnostics with each check, and
the heartbeat line in verbose mode."""

import logging
from typing import Callable, List, Sequence

from speech_event.config import SpeechEventConfig
from speech_event.interfaces.diagnostics import DIAGNOSTICS_TOPIC, NodeState, NodeStatistics, diagnostic_array
from speech_event.interfaces.periodic import Periodic
from speech_event.messages import DiagnosticArray, DiagnosticStatus
from speech_event.ports import Clock, PublisherStatus, Transport
from speech_event.topics import SIGNAL_TOPIC

_LOG = logging.getLogger("speech_event")


class Health:
    """The periodic checks of a started node."""

    def __init__(
        self,
        config: SpeechEventConfig,
        transport: Transport,
        clock: Clock,
        statistics: NodeStatistics,
        state: Callable[[PublisherStatus], NodeState],
        on_down: Callable[[], None],
        discard_reasons: Sequence[str],
    ) -> None:
        """``state(sound_detection)`` is what the node says about itself; ``on_down`` says
        soundDetection is down; ``discard_reasons`` name why the screen may not transcribe an
        utterance (each has its count in /diagnostics)."""
        self._config = config
        self._transport = transport
        self._clock = clock
        self._statistics = statistics
        self._state = state
        self._on_down = on_down
        self._discard_reasons = list(discard_reasons)
        self.sound_detection = PublisherStatus.CONNECTED  # as the last check found it
        self._periodic: List[Periodic] = []

    def start(self, started_at: float) -> None:
        """Check every health_check_period from ``started_at``; beat every heartbeat_msg_period
        in verbose mode."""
        diagnostics = self._transport.advertise(DIAGNOSTICS_TOPIC, DiagnosticArray)

        def check() -> None:
            self.check()
            diagnostics.publish(diagnostic_array(self._clock.now(), self.status()))

        self._periodic.append(Periodic(self._clock, self._config.health_check_period, check, started_at))
        if self._config.verbose_mode and self._config.heartbeat_msg_period > 0:
            self._periodic.append(
                Periodic(self._clock, self._config.heartbeat_msg_period, self.heartbeat, started_at)
            )

    def stop(self) -> None:
        """No more checks."""
        for periodic in self._periodic:
            periodic.cancel()

    def check(self) -> None:
        """Ask the transport whether soundDetection publishes; say so when it does not."""
        status = self._transport.publisher_status(SIGNAL_TOPIC)
        self.sound_detection = status
        if not status.up:
            self._on_down()
            _LOG.warning("soundDetection is down on %s: %s", SIGNAL_TOPIC, status.value)

    def status(self) -> DiagnosticStatus:
        """The node's /diagnostics status now."""
        state = self._state(self.sound_detection)
        return self._statistics.status(state, self._discard_reasons)

    def heartbeat(self) -> None:
        """Log that the node runs, with what it has done."""
        activity = self._state(self.sound_detection)
        _LOG.info(
            "speechEvent running: %d utterances so far, rejected messages %s, clipped messages %d, "
            "%.1f s of speech waiting for recognition, %d dropped (max_backlog), %d timed out",
            activity.utterances,
            {reason: count for reason, count in activity.rejected.items() if count},
            activity.clipped,
            activity.queued_seconds,
            activity.dropped,
            activity.timed_out,
        )
