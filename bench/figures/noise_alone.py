"""What the node publishes for noise alone in free speech (python -m bench.figures.noise_alone), issue 57
item 2: 30 s of each noise (white, pink, brown, babble: six people talking) at -40, -30 and -20
dBFS, sent as soundDetection sends it (48 kHz blocks, the in-memory bus, a fake clock), per
engine; every text it published, of the utterances the 30 s were cut into. The robot's
configuration (no grammar, text_style robot), every utterance answered (publish_unrecognized
false: nothing is published for one where nothing was said). Printed; nothing is asserted.

    python -m bench.figures.noise_alone [--engines "tiny.en int8,pocketsphinx"] [--seconds 30]
"""

import argparse
import dataclasses
import zlib

import numpy as np

from bench.figures.grammar import RATE, NodeRun, engine_config
from fixtures.noises import NOISE_KINDS, at_level
from harness.behaviour_controller import NOTHING, conclusion
from harness.catalog import ScenarioEngines

LEVELS = (-40.0, -30.0, -20.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--engines", default="tiny.en int8,pocketsphinx")
    parser.add_argument("--seconds", type=float, default=30.0)
    arguments = parser.parse_args()
    for name in arguments.engines.split(","):
        recognizer, config = engine_config(name.strip())
        config = dataclasses.replace(config, publish_unrecognized=False)
        print(f"{name}: texts published for {arguments.seconds:g} s of noise alone")
        with ScenarioEngines(recognizer, config, simulated=True) as engines:
            run = NodeRun(engines.build(), config)
            for kind in NOISE_KINDS:
                for level in LEVELS:
                    rng = np.random.default_rng(zlib.crc32(f"{kind}{level}".encode()))
                    texts = run.heard(at_level(kind, round(arguments.seconds * RATE), level, RATE, rng))
                    concluded = [found for found in map(conclusion, texts) if found != NOTHING]
                    print(
                        f"  {kind:<7} {level:>4.0f} dBFS  {texts!r}  the robot concludes {concluded}",
                        flush=True,
                    )


if __name__ == "__main__":
    main()
