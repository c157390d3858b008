"""``python -m harness``: replay scenario files, or run the demo."""

import argparse
import logging
import sys
from contextlib import ExitStack
from typing import Callable, List, Optional

from harness.catalog import VOICES
from harness.memory_runner import Published, run_in_memory
from harness.report import passed, report
from harness.scenario import ReplayError, Say, Scenario, ScenarioError, load_scenario
from speech_event.config import ConfigError, SpeechEventConfig, load_config

USAGE_ERROR = 2
INTERRUPTED = 130


def _base_config(path: Optional[str]) -> SpeechEventConfig:
    return load_config(path) if path else SpeechEventConfig()


def _replays(arguments: argparse.Namespace, stack: ExitStack) -> Callable[[Scenario], List[Published]]:
    """How to play one scenario on the chosen transport."""
    if arguments.transport == "memory":
        return run_in_memory
    from harness.ros_runner import RosOptions, RosReplay  # needs rospy: only for --transport ros

    options = RosOptions(arguments.real_time, arguments.node_command, arguments.config)
    replay = RosReplay(stack, options)
    return lambda scenario: replay.play(scenario, scenario.source)


def _run(arguments: argparse.Namespace) -> int:
    base = _base_config(arguments.config)
    scenarios = [load_scenario(path, base) for path in arguments.files]
    failures = 0
    with ExitStack() as stack:
        play = _replays(arguments, stack)
        for scenario in scenarios:
            published = play(scenario)
            print(report(scenario, published), flush=True)
            failures += not passed(scenario, published)
    print(f"{len(scenarios) - failures} passed, {failures} failed")
    return 1 if failures else 0


def _demo(arguments: argparse.Namespace) -> int:
    config = _base_config(arguments.config)
    problem = VOICES["tones"].problem_with(arguments.text)
    if problem:
        raise ScenarioError(f"demo text {arguments.text!r}: the tones voice {problem}")
    scenario = Scenario(
        name="demo",
        source="demo",
        config=config,
        steps=(Say(arguments.text),),
        expected=(arguments.text,),
    )
    print(
        f"soundDetection says {arguments.text!r} "
        f"({scenario.voice} voice, {config.sample_rate} Hz, 4096-sample blocks)"
    )
    for message in run_in_memory(scenario):
        print(f"/speechEvent/text at t={message.time:.3f} s: {message.text!r}")
    return 0


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m harness", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="replay scenario files and check what the node publishes")
    run.add_argument("files", nargs="+", metavar="FILE.toml")
    run.add_argument("--transport", choices=["memory", "ros"], default="memory")
    run.add_argument(
        "--real-time", action="store_true", help="ros: play on the wall clock instead of driving /clock"
    )
    run.add_argument(
        "--node-command",
        help="ros: run the scenarios against this command instead of our node ({config} = its config file)",
    )
    run.add_argument("-c", "--config", help="configuration file the scenarios' [config] overrides")
    run.set_defaults(handler=_run)
    demo = commands.add_parser("demo", help="speech in, text out: the node on the in-memory bus")
    demo.add_argument("text", nargs="?", default="go to the kitchen")
    demo.add_argument("-c", "--config", help="configuration file (default: embedded defaults)")
    demo.set_defaults(handler=_demo)
    arguments = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    try:
        return int(arguments.handler(arguments))
    except (ConfigError, ScenarioError) as problem:
        print(f"error: {problem}", file=sys.stderr)
        return USAGE_ERROR
    except ReplayError as problem:
        print(f"error: the replay could not go on: {problem}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # every process the replay started has been stopped by now
        print("interrupted", file=sys.stderr)
        return INTERRUPTED
