"""The Speech Event node configured as a scenario says (base config + its [config]), for the
test-harness launch file: a launch file cannot read a scenario's TOML."""

import argparse
import sys
from typing import List, Optional

from harness.catalog import engine_for
from harness.scenario import ScenarioError, add_scenario_arguments, scenario_from_arguments
from speech_event.application import build_recognizer, build_screen, run, stop_on_ctrl_c, without_remappings
from speech_event.errors import ConfigError


def main(argv: Optional[List[str]] = None) -> int:
    stop_on_ctrl_c()
    parser = argparse.ArgumentParser(prog="speech_event_scenario_node")
    add_scenario_arguments(parser)
    arguments = parser.parse_args(without_remappings(argv))
    try:
        scenario = scenario_from_arguments(arguments)
        engine, config = engine_for(scenario.recognizer, scenario.config)
        recognizer = build_recognizer(config, engine)
        screen = build_screen(config)
    except (ConfigError, ScenarioError) as problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    run(config, recognizer, engine, screen)
    return 0
