"""The deployment node: ``speech-event -c CONFIG`` (or scripts/speech_event_application.py).

Reads the configuration and loads the speech engine before touching ROS, so a bad file, model or
grammar stops it with status 2 and one clear message. On SIGINT it stops its timers and gives the
running recognition 2 s to finish.
"""

import argparse
import logging
import signal
import sys
from typing import List, Optional

from speech_event.config import SpeechEventConfig, load_config
from speech_event.errors import ConfigError, ModelError, StorageError
from speech_event.pipeline.screen import SpeechScreen, speech_screen_for
from speech_event.pipeline.storage import check_storage_dir
from speech_event.ports import Recognizer
from speech_event.recognizers import RECOGNIZERS, engine_builder

NODE_NAME = "speechEvent"
# What ``run`` imports from ROS 1: a missing one means no ROS here, not a bug.
ROS_MODULES = {
    "rospy",
    "rosgraph",
    "rospkg",
    "actionlib",
    "actionlib_msgs",
    "diagnostic_msgs",
    "std_msgs",
    "genpy",
}
SHUTDOWN_GRACE_SECONDS = 2.0
INTERRUPTED = 130  # the shell's status for a process ended by SIGINT
ROS_NEEDED = (
    "error: the node needs ROS 1 (rospy, actionlib, diagnostic_msgs), which this Python cannot import "
    "({problem}); see README.md, 'On ROS and on the robot'"
)


def _arguments(argv: List[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="speech-event", description="The Speech Event ROS node.")
    parser.add_argument(
        "-c",
        "--config",
        help="configuration file (default: the embedded defaults, config/speech_event_configuration.ini)",
    )
    parser.add_argument(
        "--recognizer",
        choices=sorted(RECOGNIZERS),
        default="auto",
        help="speech engine (default auto: the model of the family 'model' names when the language's "
        "path is set, NeMo or Whisper, else pocketsphinx for English); 'fake' decodes the tones voice "
        "(scenario replay)",
    )
    return parser.parse_args(argv)


def build_recognizer(config: SpeechEventConfig, name: str) -> Recognizer:
    """The engine, or ConfigError with what is wrong with its model or grammar."""
    try:
        return RECOGNIZERS[name](config)
    except ModelError as problem:
        raise ConfigError(str(problem)) from None


def build_screen(config: SpeechEventConfig) -> SpeechScreen:
    """What decides an utterance is not speech, or ConfigError (the VAD model is missing)."""
    try:
        return speech_screen_for(config)
    except ModelError as problem:
        raise ConfigError(str(problem)) from None


def run(config: SpeechEventConfig, recognizer: Recognizer, name: str, screen: SpeechScreen) -> None:
    """Run the node on ROS until it shuts down, then give recognition SHUTDOWN_GRACE_SECONDS to finish."""
    # Only the ROS entry point needs the ROS adapters (and so rospy).
    from speech_event.adapters.executors import ThreadExecutor
    from speech_event.adapters.ros import (
        RosClock,
        RosTransport,
        announce_start,
        signals_held,
        start_ros_node,
        wait_for_master,
        wait_for_shutdown,
    )
    from speech_event.node import SpeechEventNode

    wait_for_master(lambda line: print(line, file=sys.stderr, flush=True))
    start_ros_node(NODE_NAME, verbose=config.verbose_mode)
    executor = ThreadExecutor()
    with signals_held():  # a Ctrl-C during registration would deadlock rospy: it comes after
        # Every check ends within its period, whatever the network does to the master.
        transport = RosTransport(master_timeout=min(1.0, config.health_check_period / 2))
        node = SpeechEventNode(
            config, transport, RosClock(), recognizer, executor, engine_builder(name, config), screen
        )
        node.start()
        announce_start(node.started_at)
    wait_for_shutdown()
    node.stop()
    logger = logging.getLogger("speech_event")
    if not executor.shutdown(SHUTDOWN_GRACE_SECONDS):
        logger.warning("abandoned a recognition still running after %.0f s", SHUTDOWN_GRACE_SECONDS)
    node.flush_storage()


def stop_on_ctrl_c() -> None:
    """Ctrl-C (SIGINT) raises KeyboardInterrupt, as every command here documents, also when the
    process was started with SIGINT ignored: a shell starts its background jobs so (``cmd &`` in a
    script, a CI runner's), Python then leaves it ignored, and SIGINT did nothing: the driver and
    the harness ran on, and a replay waited out its grace period for each stand-in it stopped."""
    signal.signal(signal.SIGINT, signal.default_int_handler)


def without_remappings(argv: Optional[List[str]]) -> List[str]:
    """The command line (sys.argv by default) without rospy's remappings (name:=value, __name:=...)."""
    return [word for word in (sys.argv[1:] if argv is None else argv) if ":=" not in word]


def main(argv: Optional[List[str]] = None) -> int:
    """The ``speech-event`` command (the node, or export-nemo, export-whisper, pull); returns its status."""
    stop_on_ctrl_c()
    raw = without_remappings(argv)
    if raw[:1] == ["export-nemo"]:
        from speech_event.exporters.nemo import main as export_nemo

        return export_nemo(raw[1:])
    if raw[:1] == ["export-whisper"]:
        from speech_event.exporters.whisper import main as export_whisper

        return export_whisper(raw[1:])
    if raw[:1] == ["pull"]:
        from speech_event.models.pull import main as pull

        return pull(raw[1:])
    arguments = _arguments(raw)
    try:
        config = load_config(arguments.config) if arguments.config else SpeechEventConfig()
        recognizer = build_recognizer(config, arguments.recognizer)
        screen = build_screen(config)
        if config.audio_storage_dir:
            check_storage_dir(config.audio_storage_dir)
    except (ConfigError, StorageError) as problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    try:
        run(config, recognizer, arguments.recognizer, screen)
    except KeyboardInterrupt:  # before the node registered: waiting for the master
        print("interrupted before the ROS master answered", file=sys.stderr)
        return INTERRUPTED
    except ImportError as problem:  # no ROS 1 here: one line, not rospy's traceback
        if problem.name is None or problem.name.split(".")[0] not in ROS_MODULES:
            raise
        print(ROS_NEEDED.format(problem=problem), file=sys.stderr)
        return 2
    return 0
