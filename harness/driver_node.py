"""``speech-event-driver -c config/speech_event_driver.ini [SOURCE]``: soundDetection from a laptop.

It publishes mono float32 blocks on /soundDetection/signal as the robot's soundDetection does, only
while its gate hears speech (harness/gate.py), from one of three sources:

- the microphone (``mode mic``, no SOURCE): any PortAudio input device (harness/microphone.py);
- an audio file (SOURCE: WAV, FLAC, OGG, ...), played on the wall clock;
- a scenario file (SOURCE ending in .toml): its speech, silences and outages on the wall clock.

On ROS (the default) it is the node ``soundDetection``; with ``--transport memory`` it runs Speech
Event itself on the in-memory bus in the same process and prints what it publishes: no roscore.
"""

import argparse
import sys
import threading
import time
from contextlib import ExitStack
from typing import Callable, List, Optional, Tuple

from harness.driver import DRIVER_FORMAT, AudioFileError, DriverConfig, gate_settings, play, read_audio
from harness.gate import Piece, SpeechGate
from harness.link import Link
from harness.microphone import Microphone, MicrophoneError, describe_devices, input_devices, load_sounddevice
from harness.scenario import ScenarioError, load_scenario
from harness.timeline import ComeUp, GoDown, Publish, build_timeline
from harness.vad_gate import VadGate
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.application import stop_on_ctrl_c, without_remappings
from speech_event.config import SpeechEventConfig, load_config
from speech_event.errors import ConfigError, ModelError
from speech_event.messages import Float32MultiArray
from speech_event.ports import Clock, Publisher

# --transport memory: the most seconds the node may take, after the source ends, to close the last
# utterance and to transcribe what is queued.
SETTLE_TIMEOUT = 60.0
USAGE_ERROR = 2


def _say(line: str) -> None:
    print(f"speech_event_driver: {line}", file=sys.stderr, flush=True)


def _memory(
    stack: ExitStack, node_config: SpeechEventConfig, recognizer_name: str
) -> Tuple[Link, Clock, Callable[[], bool]]:
    """Speech Event itself on the in-memory bus, on the wall clock; its texts printed."""
    from harness.catalog import ScenarioEngines
    from speech_event.adapters.executors import ThreadExecutor
    from speech_event.adapters.memory_bus import InMemoryBus
    from speech_event.adapters.system_clock import SystemClock
    from speech_event.messages import String
    from speech_event.node import SpeechEventNode

    bus, clock, executor = InMemoryBus(), SystemClock(), ThreadExecutor()
    bus.subscribe(TEXT_TOPIC, String, lambda m: print(f"{TEXT_TOPIC}: {m.data!r}", flush=True))  # type: ignore[attr-defined]
    engines = stack.enter_context(ScenarioEngines(recognizer_name, node_config))  # closed after finish
    node = SpeechEventNode(node_config, bus, clock, engines.build(), executor, engines.build)
    node.start()

    def finish() -> None:
        """What was said last is transcribed before the process ends: the pause after it must have
        closed the utterance (its timer thread may run late on a busy machine), then every queued
        recognition runs."""
        deadline = time.monotonic() + node_config.speech_pause_period + SETTLE_TIMEOUT
        time.sleep(node_config.speech_pause_period)
        while node.pending_samples and time.monotonic() < deadline:
            time.sleep(0.05)
        node.stop()
        executor.shutdown(SETTLE_TIMEOUT)

    stack.callback(finish)
    advertise = lambda: bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")  # noqa: E731
    return Link(advertise, lambda publisher: None), clock, lambda: False


def _gate(config: DriverConfig) -> SpeechGate:
    check = VadGate.from_config(config) if config.vad_threshold > 0 else None
    return SpeechGate(gate_settings(config), check)


def _publish(publisher: Publisher, pieces: List[Piece]) -> None:
    for _, piece in pieces:
        publisher.publish(Float32MultiArray(data=piece))


def _wait_until(clock: Clock, end: float, stopped: Callable[[], bool]) -> None:
    while clock.now() < end and not stopped():
        time.sleep(0.05)


def _play_file(
    path: str, config: DriverConfig, link: Link, clock: Clock, stopped: Callable[[], bool]
) -> None:
    audio = read_audio(path, config.sample_rate)
    published = threading.Event()
    end = play(audio, config, link.up(), clock, _gate(config), published)
    while not (published.is_set() or stopped()):  # its last pieces come late on a busy machine
        time.sleep(0.05)
    _wait_until(clock, end + 0.1, stopped)


def _play_scenario(
    path: str, config: DriverConfig, link: Link, clock: Clock, stopped: Callable[[], bool]
) -> None:
    """The scenario's soundDetection events at their times from now (messages of another type, sent
    by another node in a scenario, are left out: this driver is soundDetection)."""
    timeline = build_timeline(load_scenario(path, SpeechEventConfig(sample_rate=config.sample_rate)))
    publisher = link.up()
    start = clock.now()
    for event in timeline.events:
        _wait_until(clock, start + event.time, stopped)
        if isinstance(event, Publish) and isinstance(event.message, Float32MultiArray):
            publisher.publish(event.message)
        elif isinstance(event, GoDown):
            link.down(crash=event.kind == "crash")
        elif isinstance(event, ComeUp):
            publisher = link.up()
    _wait_until(clock, start + timeline.end, stopped)


def _listen(config: DriverConfig, link: Link, stopped: Callable[[], bool]) -> None:
    publisher, gate = link.up(), _gate(config)
    stop = threading.Event()
    microphone = Microphone(
        config, lambda audio: _publish(publisher, gate.feed(audio)), _say, load_sounddevice()
    )
    capture = threading.Thread(target=microphone.run, args=(stop,), name="microphone", daemon=True)
    capture.start()
    try:
        while capture.is_alive() and not stopped():
            time.sleep(0.1)
    finally:
        stop.set()
        capture.join(5.0)


def main(argv: Optional[List[str]] = None) -> int:
    stop_on_ctrl_c()
    parser = argparse.ArgumentParser(prog="speech_event_driver", description=__doc__)
    parser.add_argument(
        "-c", "--config", required=True, help="driver configuration (the seed's Table 2 keys)"
    )
    parser.add_argument("source", nargs="?", help="an audio file or a scenario (.toml); none: the microphone")
    parser.add_argument("--transport", choices=["ros", "memory"], default="ros")
    parser.add_argument("--node-config", help="memory: Speech Event's configuration (default: its defaults)")
    parser.add_argument("--recognizer", default="auto", help="memory: Speech Event's engine (default auto)")
    parser.add_argument("--list-devices", action="store_true", help="print the input devices and exit")
    arguments = parser.parse_args(without_remappings(argv))
    try:
        config = DRIVER_FORMAT.load(arguments.config)
        if arguments.list_devices:
            print(describe_devices(input_devices(load_sounddevice())))
            return 0
        if config.mode == "file" and not arguments.source:
            raise ConfigError(f"{arguments.config}: mode file needs a SOURCE file on the command line")
        node_config = load_config(arguments.node_config) if arguments.node_config else SpeechEventConfig()
        with ExitStack() as stack:
            if arguments.transport == "memory":
                link, clock, stopped = _memory(stack, node_config, arguments.recognizer)
            else:
                from harness.ros.driver_side import ros_side  # rospy: only on ROS

                link, clock, stopped = ros_side()
            if arguments.source is None:
                _listen(config, link, stopped)
            elif arguments.source.endswith(".toml"):
                _play_scenario(arguments.source, config, link, clock, stopped)
            else:
                _play_file(arguments.source, config, link, clock, stopped)
    except (ConfigError, AudioFileError, ScenarioError, MicrophoneError, ModelError) as problem:
        _say(f"error: {problem}")
        return USAGE_ERROR
    except KeyboardInterrupt:
        return 130
    return 0
