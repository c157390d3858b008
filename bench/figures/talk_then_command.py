"""A minute of talk with a grammar in force, then a command (python -m bench.figures.talk_then_command
[--engine NAME] [--seconds S]), issue 58 item 4: whether the talk leaves a backlog, and how soon
the command said right after it is published.

In memory, in real time (the wall clock, the thread executor: a block stops the speculation it
makes worthless, as on the robot), behind the robot's gate (bench/figures/end_of_speech.py's
``gated``: the blocks whose RMS reaches soundDetection's intensityThreshold, at their times), the
robot's 32 commands in force. The talk: people reading (pocketsphinx-testdata's cards and librivox
recordings, then LJ Speech's sentences) one after the other with 0.4 s between recordings, until
``--seconds`` of them; none says a command. Then 2 s without a block (the talk's turn ends), and a
person saying "stop" (the first of Speech Commands' development clips of it). Speculation on (the
default) and off, the command alone and after the talk, a fresh node each.

Printed per setting: the talk's length, the CPU seconds of the process from the talk's first
block to the command's (per second), the seconds of speech still waiting for recognition when the
command begins (the backlog the node reports), the texts published before the command (each a
false command), the command's text and the time from its last block to the text (the word ends
within that 85 ms block: a backlog shows here too; a rejection publishes its error, timed alike),
and speculations started and thrown away. Nothing is asserted. Needs an idle machine.
"""

import argparse
import dataclasses
import time
from typing import List, Tuple

import numpy as np

from bench.figures.end_of_speech import RATE, gated, node_on_bus
from bench.figures.grammar import ENGINES
from bench.figures.measures import robot_commands
from fixtures.noises import read_audio
from fixtures.recordings import SAMPLE_RATE, SPEECH_COMMANDS, cards, librivox, ljspeech
from harness.catalog import ScenarioEngines
from harness.processes import wait_until
from speech_event.adapters.executors import ThreadExecutor
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray
from speech_event.pipeline.resample import resample
from speech_event.ports import Recognizer
from speech_event.topics import SIGNAL_TOPIC, SPEECH_NOT_RECOGNIZED

BETWEEN_RECORDINGS = 0.4
# The talk's turn ends first (speech_pause_period, 1.5 s): else the command would end it.
BEFORE_THE_COMMAND = 2.0
COMMAND = "stop"

Blocks = List[Tuple[float, np.ndarray]]  # when each block is complete (s from the start), the block


def talk(seconds: float) -> Tuple[Blocks, float]:
    """People reading behind the gate, recordings one after the other until ``seconds`` of them:
    the blocks, and how long the talk lasts (0 s: no talk, the command alone)."""
    blocks: Blocks = []
    start = 0.0
    for recording in cards() + librivox() + ljspeech():
        if start >= seconds:
            break
        voice = resample(recording.samples(), SAMPLE_RATE, RATE)
        blocks += [(start + when, block) for when, block in gated(voice)]
        start += voice.size / RATE + BETWEEN_RECORDINGS
    return blocks, max(0.0, start - BETWEEN_RECORDINGS)


def command(after: float) -> Blocks:
    """A person saying COMMAND behind the gate, its first sample ``after`` seconds from the start."""
    path = sorted((SPEECH_COMMANDS / COMMAND).glob("*.wav"))[0]
    return [(after + when, block) for when, block in gated(read_audio(path, RATE))]


def measure(engine: Recognizer, config: SpeechEventConfig, grammar: str, seconds: float) -> str:
    """One line of figures for the talk and the command, said to a fresh node with ``config``."""
    said, talk_seconds = talk(seconds)
    said_command = command(talk_seconds + BEFORE_THE_COMMAND)
    executor = ThreadExecutor()
    node, bus, heard, _ = node_on_bus(config, engine, SystemClock(), executor, grammar)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    began, began_cpu = time.time(), time.process_time()
    sent: List[float] = []
    for when, block in said + said_command:
        time.sleep(max(0.0, began + when - time.time()))
        if len(sent) == len(said):  # the command's first block: what the talk left
            talk_cpu, queued = time.process_time() - began_cpu, node.queued_speech_seconds
        sound_detection.publish(Float32MultiArray(data=block))
        sent.append(time.time())
    wait_until(lambda: len(heard) > 0 and heard[-1][0] > sent[-1], "the command's text", 60.0)
    executor.shutdown(30.0)
    node.stop()
    during_talk = [text for when, text in heard if when < sent[len(said)]]
    false_commands = sum(text != SPEECH_NOT_RECOGNIZED for text in during_talk)
    command_at, command_text = heard[-1]
    return (
        f"talk {talk_seconds:.1f} s: {talk_cpu / (talk_seconds + BEFORE_THE_COMMAND):.2f} CPU s per s "
        f"(until the command), {queued:.1f} s of speech waiting at the command, "
        f"{len(during_talk)} texts before it ({false_commands} a command); command {command_text!r} "
        f"{command_at - sent[-1]:.2f} s after its last block; speculations "
        f"{node.speculations.started} started, "
        f"{node.speculations.started - node.speculations.used} thrown away"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="tiny.en int8", help=f"one of {', '.join(ENGINES)}")
    parser.add_argument("--seconds", type=float, default=60.0, help="of talk, at least")
    arguments = parser.parse_args()
    name, quantization = ENGINES[arguments.engine]
    base = SpeechEventConfig(
        partial_period=0.0,
        health_check_period=3600.0,
        publish_unrecognized=True,
        quantization=quantization or "none",
    )
    grammar = "|".join(robot_commands())
    with ScenarioEngines(name, base) as engines:
        engine = engines.build()
        # Warm, within the grammar: no run measured is the engine's first (the silence its evidence
        # needs is encoded as each node checks the grammar, forced.UnheardScores.prepare).
        measure(engine, base, grammar, 0.0)
        print(f"{arguments.engine}, the robot's {len(robot_commands())} commands, behind the gate, real time")
        for speculating in (True, False):
            config = dataclasses.replace(base, speculative_recognition=speculating)
            for seconds in (0.0, arguments.seconds):
                line = measure(engine, config, grammar, seconds)
                print(f"  speculation {'on ' if speculating else 'off'}: {line}", flush=True)


if __name__ == "__main__":
    main()
