"""What hosting pocketsphinx in a process of its own costs (python -m bench.figures.sphinx_process [RUNS]).

- start-up: the engine built and its first utterance (1 s) transcribed, in this process and hosted
  (a new interpreter, numpy and speech_event imported, pocketsphinx imported and its decoder made
  there), language model and cards grammar; and a child hosting an engine that imports nothing
  more (the interpreter, the pipe and speech_event.recognizers alone);
- per call: the round trip of 1 s and of 10 s of 16 kHz audio to an engine that answers at once
  (pickling, the pipe, the reply), and a real transcription of each, hosted against in this
  process (the difference is within the decoding's own spread);
- stall: the longest a thread of this process waking every 5 ms waited while 7 s were transcribed.

Medians of RUNS (5) runs, min and max beside; the figures of one group are taken in turns.
"""

import functools
import statistics
import sys
import time
from typing import Callable, Dict, List, Union

import numpy as np

from fixtures import recordings
from fixtures.load import longest_stall
from speech_event.grammar import load_grammar
from speech_event.ports import Audio, Transcript
from speech_event.recognizers.engine_process import EngineProcess
from speech_event.recognizers.sphinx import SphinxRecognizer
from speech_event.recognizers.sphinx_process import SphinxProcess

Engine = Union[SphinxRecognizer, SphinxProcess]


class Sink:
    """An engine that answers at once: what remains of a call is the crossing."""

    sample_rate = 16000

    def transcribe(self, audio: Audio) -> Transcript:
        return Transcript("")


def _rows(runs: int, measures: Dict[str, Callable[[], float]]) -> Dict[str, List[float]]:
    """Each of ``measures`` (seconds) ``runs`` times, taken in turns so that a change in the
    machine's load falls on all alike; printed as median, min and max, and returned."""
    seconds: Dict[str, List[float]] = {label: [] for label in measures}
    for _ in range(runs):
        for label, measure in measures.items():
            seconds[label].append(measure())
    for label, values in seconds.items():
        _print(label, values)
    return seconds


def _print(label: str, seconds: List[float]) -> None:
    median, low, high = (1000 * value for value in (statistics.median(seconds), min(seconds), max(seconds)))
    print(f"  {label:34} {median:8.1f} ms  ({low:.1f} to {high:.1f})")


def _timed(action: Callable[[], object]) -> Callable[[], float]:
    """How long ``action`` takes, as a measure for _row."""

    def measure() -> float:
        began = time.perf_counter()
        action()
        return time.perf_counter() - began

    return measure


def _first_utterance(build: Callable[[], Engine], audio: np.ndarray) -> float:
    began = time.perf_counter()
    engine = build()
    engine.transcribe(audio)
    took = time.perf_counter() - began
    if isinstance(engine, SphinxProcess):
        engine.close()
    return took


def main(runs: int) -> None:
    # Under its module's name: run as __main__, this module's Sink pickles as __main__.Sink, which
    # the child (whose __main__ is its bootstrap) cannot find.
    from bench.figures.sphinx_process import Sink

    speech = np.concatenate([recording.samples() for recording in recordings.librivox()])
    one, ten, seven = speech[:16000], speech[: 10 * 16000], recordings.librivox()[0].samples()
    cards = load_grammar(recordings.CARDS_GRAMMAR)
    print(f"start-up, to the first text of 1 s (median of {runs}, min to max)")
    builders: Dict[str, Callable[[], Engine]] = {
        "language model, in process": SphinxRecognizer,
        "language model, hosted": SphinxProcess,
        "cards grammar, in process": lambda: SphinxRecognizer(cards),
        "cards grammar, hosted": lambda: SphinxProcess(cards),
    }
    starts = {label: functools.partial(_first_utterance, build, one) for label, build in builders.items()}
    _rows(runs, {**starts, "a child alone": _timed(lambda: EngineProcess("sink", Sink).close())})

    print("per call (hosted - in process: the median of the runs' differences)")
    with SphinxProcess() as hosted:
        sink = EngineProcess("sink", Sink)
        in_process = SphinxRecognizer()
        hosted.transcribe(one)
        in_process.transcribe(one)
        for name, audio in (("1 s", one), ("10 s", ten)):
            calls = _rows(
                runs,
                {
                    f"{name}: crossing only": _timed(functools.partial(sink.call, "transcribe", audio)),
                    f"{name}: transcribe in process": _timed(functools.partial(in_process.transcribe, audio)),
                    f"{name}: transcribe hosted": _timed(functools.partial(hosted.transcribe, audio)),
                },
            )
            differences = zip(calls[f"{name}: transcribe hosted"], calls[f"{name}: transcribe in process"])
            _print(f"{name}: hosted - in process", [out - within for out, within in differences])
        sink.close()

        print("longest stall of a 5 ms ticker while 7 s are transcribed")
        _rows(
            runs,
            {
                "in process": functools.partial(longest_stall, in_process, seven),
                "hosted": functools.partial(longest_stall, hosted, seven),
            },
        )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
