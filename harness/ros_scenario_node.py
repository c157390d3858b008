"""The Speech Event node configured as a scenario says (base config + its [config]), for the
test-harness launch file: a launch file cannot read a scenario's TOML."""

import argparse
import sys
from typing import List, Optional

from harness.catalog import engine_for
from harness.scenario import ScenarioError, load_scenario
from speech_event.application import build_recognizer, run
from speech_event.config import ConfigError, SpeechEventConfig, load_config


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="speech_event_scenario_node")
    parser.add_argument("scenario")
    parser.add_argument("-c", "--config", help="configuration the scenario's [config] overrides")
    raw = sys.argv[1:] if argv is None else argv
    arguments = parser.parse_args([word for word in raw if ":=" not in word])
    try:
        base = load_config(arguments.config) if arguments.config else SpeechEventConfig()
        scenario = load_scenario(arguments.scenario, base)
        engine, config = engine_for(scenario.recognizer, scenario.config)
        recognizer = build_recognizer(config, engine)
    except (ConfigError, ScenarioError) as problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    run(config, recognizer)
    return 0
