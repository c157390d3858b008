"""End of turn at the end of speech (``end_of_speech``, speech_event/turns/end_of_turn.py) through the
node on the fake clock: the turn ends where the speech ended once the text up to there is complete,
the room after it is not transcribed, speech that goes on is kept, and however long the engine
takes, the same blocks give the same texts."""

import dataclasses
from typing import Callable, List, Optional, Tuple

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.audio import noise, speak_tones
from fixtures.paths import ROOT
from fixtures.rig import AT_16K, Rig
from harness.memory_runner import run_in_memory
from harness.scenario import load_scenario
from speech_event.config import GRAMMAR_END_OF_SPEECH, SpeechEventConfig, end_of_speech_seconds
from speech_event.grammar import Grammar
from speech_event.interfaces.diagnostics import DISCARDED_AFTER_SPEECH
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_GRAMMAR_SERVICE
from speech_event.messages import SetEnabledRequest, SetGrammarRequest
from speech_event.ports import Recognizer, Stoppable, Transcript
from speech_event.recognizers.tones import WORD_GAP_SECONDS, ToneRecognizer
from speech_event.turns.speech_end import AVERAGED_FRAMES

RATE = 16000
BLOCK = 1024  # 64 ms
FRAME = 320  # the end of speech's 20 ms frames
# Health checks each second: /diagnostics counts the utterances discarded.
CONFIG = dataclasses.replace(AT_16K, end_of_speech=0.3, partial_period=0.0, health_check_period=1.0)
COMMANDS = "go to the kitchen|stop|yes"


def _room(seconds: float, seed: int = 0) -> np.ndarray:
    return noise(int(seconds * RATE), -50.0, np.random.default_rng(seed))


def _speech(*parts: object) -> np.ndarray:
    """Words (str, in the tones voice) and seconds of room sound (float), one after the other."""
    pieces = [
        speak_tones(part, RATE) if isinstance(part, str) else _room(float(part), seed=index)  # type: ignore[arg-type]
        for index, part in enumerate(parts)
    ]
    return np.concatenate(pieces).astype(np.float32)


class CannotBeStopped:
    """The tones engine as one that cannot be stopped, as pocketsphinx (no ``stop``): it speculates
    only on the audio up to the end of speech."""

    sample_rate = ToneRecognizer.sample_rate

    def __init__(self) -> None:
        self._engine = ToneRecognizer()

    def check_grammar(self, grammar: Grammar) -> None:
        self._engine.check_grammar(grammar)

    def use_grammar(self, grammar: Optional[Grammar]) -> None:
        self._engine.use_grammar(grammar)

    def transcribe(self, audio: np.ndarray) -> Transcript:
        return self._engine.transcribe(audio)


Engine = Callable[[], Recognizer]
ENGINES: List[Engine] = [ToneRecognizer, CannotBeStopped]


def _run(
    config: object,
    audio: np.ndarray,
    grammar: str = COMMANDS,
    job_seconds: float = 0.0,
    engine: Engine = ToneRecognizer,
) -> Rig:
    rig = Rig(config, engine(), job_seconds=job_seconds)  # type: ignore[arg-type]
    if grammar:
        assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(grammar)).response == 1  # type: ignore[attr-defined]
    rig.speak(audio, BLOCK)
    rig.clock.advance(config.speech_pause_period + job_seconds * 4 + 1.0)  # type: ignore[attr-defined]
    return rig


def _last_block(audio: np.ndarray) -> float:
    """When ``_run`` sends the last block of ``audio`` (its blocks one after the other)."""
    return -(-audio.size // BLOCK) * BLOCK / RATE


def _timed(rig: Rig) -> List[Tuple[float, str]]:
    return [(round(when, 6), text) for when, text in rig.published]


def _discarded_after_speech(rig: Rig) -> int:
    values = {value.key: value.value for value in rig.diagnostics[-1].status[0].values}
    return int(values[f"utterances discarded: {DISCARDED_AFTER_SPEECH}"])


def test_a_command_is_published_when_the_speech_ends_not_after_the_room_sound_and_the_pause() -> None:
    audio = _speech("stop", 1.0)
    tones_end = speak_tones("stop", RATE).size - int(WORD_GAP_SECONDS * RATE)  # silence, then the room
    ended = _run(CONFIG, audio)
    waited = _run(dataclasses.replace(CONFIG, end_of_speech=0.0), audio)
    # The last 20 ms frame the tones reach, and two more (averaged over five, they are speech
    # too); then 0.3 s of frames of the room: the block that holds them, on the block clock.
    speech_ends = ((tones_end - 1) // FRAME + AVERAGED_FRAMES // 2 + 1) * FRAME
    heard = speech_ends + int(0.3 * RATE)
    heard_block = -(-heard // BLOCK)
    assert _timed(ended) == [(round(heard_block * BLOCK / RATE, 6), "stop")]
    last_block = _last_block(audio)
    assert _timed(waited) == [(round(last_block + CONFIG.speech_pause_period, 6), "stop")]


def test_the_room_after_the_turn_is_not_transcribed() -> None:
    rig = _run(CONFIG, _speech("stop", 1.0))
    assert rig.texts() == ["stop"]
    assert _discarded_after_speech(rig) == 1


def test_a_pause_inside_a_phrase_does_not_end_the_turn_when_the_words_so_far_are_no_phrase() -> None:
    rig = _run(CONFIG, _speech("go", 0.5, "to the kitchen", 1.0))
    assert rig.texts() == ["go to the kitchen"]


def test_speech_after_a_complete_phrase_is_the_next_utterance() -> None:
    rig = _run(CONFIG, _speech("stop", 0.5, "yes", 1.0))
    assert rig.texts() == ["stop", "yes"]


class _Given(ToneRecognizer):
    """The tones engine, keeping each stretch of audio it is given."""

    def __init__(self) -> None:
        super().__init__()
        self.given: List[np.ndarray] = []

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self.given.append(np.array(audio))
        return super().transcribe(audio)


def _starts(audio: np.ndarray, given: List[np.ndarray]) -> List[Tuple[int, int]]:
    """Where in ``audio`` each stretch given to the engine begins and ends (room noise makes the
    first 64 samples of a stretch occur once)."""
    windows = np.lib.stride_tricks.sliding_window_view(audio, 64)
    found = []
    for stretch in given:
        (start,) = np.flatnonzero((windows == stretch[:64]).all(axis=1))
        assert np.array_equal(audio[start : start + stretch.size], stretch)
        found.append((int(start), int(start + stretch.size)))
    return found


def test_what_follows_the_cut_begins_the_next_utterance_so_no_audio_is_lost_between_turns() -> None:
    audio = _speech(0.2, "stop", 0.5, "yes", 1.0)  # each stretch then begins in room noise
    engine = _Given()
    rig = Rig(CONFIG, engine)
    assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(COMMANDS)).response == 1  # type: ignore[attr-defined]
    rig.speak(audio, BLOCK)
    rig.clock.advance(CONFIG.speech_pause_period + 1.0)
    assert rig.texts() == ["stop", "yes"]
    stretches = set(_starts(audio, engine.given))  # utterances and speculations on them
    starts = sorted({start for start, _ in stretches})
    assert len(starts) == 2  # "stop" and "yes": the room after it is neither transcribed nor speculated on
    for before, after in zip(starts, starts[1:]):
        # an utterance begins where the one before it was cut: no sample between them is lost
        assert after in {end for start, end in stretches if start == before}


def _room_then_a_gap_then(word: str, config: SpeechEventConfig) -> Tuple[Rig, _Given]:
    """0.5 s of the room's blocks (a noisy room through the gate), 0.5 s without a block, ``word``'s
    blocks and 1 s of the room's, in the command grammar."""
    engine = _Given()
    rig = Rig(config, engine)
    assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(COMMANDS)).response == 1  # type: ignore[attr-defined]
    rig.speak(_room(0.5), BLOCK)
    rig.clock.advance(0.5)
    rig.speak(_speech(word, 1.0), BLOCK)
    rig.clock.advance(config.speech_pause_period + 1.0)
    return rig, engine


def test_where_the_end_of_speech_decides_no_speculation_runs_on_audio_without_speech() -> None:
    # Issue 58: the room before the word (no decision is made on it, and the word makes a
    # speculation on it worthless) and the room after the cut (a pause throws it away).
    rig, engine = _room_then_a_gap_then("stop", CONFIG)
    assert rig.texts() == ["stop"]
    assert rig.node.speculations.started == 1  # on the utterance up to the cut after "stop"
    assert len(engine.given) == 1
    # Waiting for the pause instead, the node speculates at each gap: on the room alone, then on
    # the room and "stop" (the room after it is the same utterance).
    waited, waited_engine = _room_then_a_gap_then("stop", dataclasses.replace(CONFIG, end_of_speech=0.0))
    assert waited.texts() == ["stop"]
    assert waited.node.speculations.started == 2
    room = int(0.5 * RATE)
    assert [stretch.size for stretch in waited_engine.given] == [room, room + _speech("stop", 1.0).size]


def test_in_free_speech_a_complete_answer_ends_the_turn_and_other_words_wait_for_the_pause() -> None:
    answer = _run(CONFIG, _speech("yes", 1.0), grammar="")
    other = _run(CONFIG, _speech("maybe", 1.0), grammar="")
    assert [text for _, text in answer.published] == ["yes"]
    assert [text for _, text in other.published] == ["maybe"]
    assert answer.published[0][0] < 1.0 < other.published[0][0]


@pytest.mark.parametrize("engine", ENGINES, ids=lambda engine: engine.__name__)
def test_blocks_that_stop_with_the_speech_end_the_turn_end_of_speech_after_the_last(engine: Engine) -> None:
    audio = _speech("stop")
    rig = _run(CONFIG, audio, engine=engine)
    last_block = _last_block(audio)
    assert _timed(rig) == [(round(last_block + end_of_speech_seconds(CONFIG), 6), "stop")]


@pytest.mark.parametrize(
    ("speculation_gap", "job_seconds", "after_the_last_block"),
    [
        pytest.param(0.3, 0.15, 0.45, id="speculating_at_the_end_the_text_comes_once_the_engine_is_done"),
        pytest.param(0.1, 0.15, 0.3, id="speculating_at_speculation_gap_the_text_is_ready_at_the_end"),
        pytest.param(0.1, 0.25, 0.35, id="or_comes_as_soon_as_the_engine_is_done"),
    ],
)
def test_with_blocks_that_stop_with_the_speech_the_speculation_starts_at_speculation_gap(
    speculation_gap: float, job_seconds: float, after_the_last_block: float
) -> None:
    audio = _speech("stop")
    rig = _run(dataclasses.replace(CONFIG, speculation_gap=speculation_gap), audio, job_seconds=job_seconds)
    last_block = _last_block(audio)
    assert _timed(rig) == [(round(last_block + after_the_last_block, 6), "stop")]
    assert rig.node.speculations.started == 1  # on the whole utterance, the cut of the decision


SAID: List[Tuple[object, ...]] = [
    ("stop", 1.0),
    ("go", 0.5, "to the kitchen", 0.4),
    ("stop", 0.35, "yes", 0.31, "stop", 1.0),
    ("yes", 0.2, "stop", 0.6, "go", 0.32, "to the kitchen"),
]


@settings(max_examples=25, deadline=None)
@given(st.sampled_from(SAID), st.sampled_from([COMMANDS, ""]), st.floats(0.0, 2.5), st.sampled_from(ENGINES))
def test_however_long_the_engine_takes_the_same_blocks_give_the_same_texts(
    said: Tuple[object, ...], grammar: str, job_seconds: float, engine: Engine
) -> None:
    audio = _speech(*said)
    at_once = _run(CONFIG, audio, grammar, engine=engine)
    slow = _run(CONFIG, audio, grammar, job_seconds, engine)
    assert slow.texts() == at_once.texts()
    assert _discarded_after_speech(slow) == _discarded_after_speech(at_once)


WORDS = ("stop", "yes", "go", "to the kitchen", "maybe")


def _spoken_with_gaps(
    config: object,
    turns: List[Tuple[str, float]],
    grammar: str,
    job_seconds: float,
    engine: Engine = ToneRecognizer,
) -> Rig:
    """Each word's blocks, then that many seconds without a block (the robot's gate)."""
    rig = Rig(config, engine(), job_seconds=job_seconds)  # type: ignore[arg-type]
    if grammar:
        assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(grammar)).response == 1  # type: ignore[attr-defined]
    for word, gap in turns:
        rig.speak(speak_tones(word, RATE), BLOCK)
        rig.clock.advance(gap)
    rig.clock.advance(config.speech_pause_period + job_seconds * 2 * len(turns) + 1.0)  # type: ignore[attr-defined]
    return rig


class ClosingSentences(ToneRecognizer):
    """The tones engine as one that closes sentences (ClosesSentences, as Whisper)."""

    def closes_sentences(self) -> bool:
        return True


def test_left_to_its_default_free_speech_with_an_engine_that_closes_sentences_ends_at_the_end_of_speech() -> (
    None
):
    # turn_end_model auto: Smart Turn hears English with such an engine (installed in this env); a
    # complete answer ends the turn at once, in the room sound after it, long before the pause
    assert DEFAULT.turn_end_model == "auto"
    audio = _speech("yes", 1.0)
    ended = _run(DEFAULT, audio, grammar="", engine=ClosingSentences)
    assert ended.texts() == ["yes"] and ended.published[0][0] < _last_block(audio)
    # Kinyarwanda (not among Smart Turn's languages) and turn_end_model none wait for the pause
    for config in (
        dataclasses.replace(DEFAULT, language="kinyarwanda"),
        dataclasses.replace(DEFAULT, turn_end_model="none"),
    ):
        waited = _run(config, audio, grammar="", engine=ClosingSentences)
        assert _timed(waited) == [(round(_last_block(audio) + DEFAULT.speech_pause_period, 6), "yes")]


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(st.sampled_from(WORDS), st.floats(0.0, 1.2)), min_size=1, max_size=4),
    st.sampled_from([COMMANDS, ""]),
    st.sampled_from([0.5, 1.5]),
    st.floats(0.0, 2.5),
    st.sampled_from([0.1, 0.3]),
    st.sampled_from(ENGINES),
)
def test_with_gaps_between_blocks_however_long_the_engine_takes_the_texts_are_the_same(
    turns: List[Tuple[str, float]],
    grammar: str,
    pause: float,
    job_seconds: float,
    speculation_gap: float,
    engine: Engine,
) -> None:
    config = dataclasses.replace(CONFIG, speech_pause_period=pause)
    at_once = _spoken_with_gaps(config, turns, grammar, 0.0, engine)
    slow = _spoken_with_gaps(
        dataclasses.replace(config, speculation_gap=speculation_gap), turns, grammar, job_seconds, engine
    )
    assert slow.texts() == at_once.texts()


def test_the_text_is_ready_when_the_end_is_heard_if_the_engine_takes_less_than_the_wait_after_the_pad() -> (
    None
):
    audio = _speech("stop", 1.0)
    at_once = _run(CONFIG, audio)
    taking_a_tenth = _run(CONFIG, audio, job_seconds=0.1)  # started once the cut's pad (0.15 s) was taken
    assert _timed(taking_a_tenth) == _timed(at_once)


# Every scenario with the turn ending at the end of speech: tests/test_every_scenario.py, on the
# engines of its other runs of the scenario.


def test_an_engine_that_cannot_be_stopped_speculates_only_on_the_audio_up_to_the_end_of_speech() -> None:
    assert not isinstance(CannotBeStopped(), Stoppable)
    # "stop", 0.35 s of room (an end heard, a cut decided: the phrase is complete), then "yes"
    # with blocks that stop with it (the end heard in the pause in blocks).
    rig = _run(CONFIG, _speech("stop", 0.35, "yes"), engine=CannotBeStopped)
    assert rig.texts() == ["stop", "yes"]
    assert rig.node.speculations.started == 2  # one for each cut, none at speculation_gap alone
    without = dataclasses.replace(CONFIG, end_of_speech=0.0)
    off = _run(without, _speech("stop", 0.35, "yes"), engine=CannotBeStopped)
    assert off.texts() == []  # one utterance, "stop yes": no phrase of the grammar
    assert off.node.speculations.started == 0
    # In free speech it does not decide (its text is never a closed sentence): the pause ends it.
    free = _run(CONFIG, _speech("stop", 0.35, "yes"), grammar="", engine=CannotBeStopped)
    assert free.texts() == ["stop yes"]
    assert free.node.speculations.started == 0


def test_an_engine_that_cannot_be_stopped_decides_once_an_utterance() -> None:
    # The first end heard ("go": no phrase) is decided and the turn goes on; the next end waits
    # for the pause. The engine that can be stopped decides it, and ends the turn there.
    audio = _speech("go", 0.5, "to the kitchen", 1.0)
    once = _run(CONFIG, audio, engine=CannotBeStopped)
    each = _run(CONFIG, audio)
    assert once.texts() == each.texts() == ["go to the kitchen"]
    assert once.node.speculations.started == 1
    last_block = _last_block(audio)
    assert _timed(once) == [(round(last_block + CONFIG.speech_pause_period, 6), "go to the kitchen")]
    assert each.published[0][0] < last_block  # inside the room sound after the words


def test_pocketsphinx_decides_on_the_end_of_speech_in_grammar_mode_once_an_utterance() -> None:
    # scenarios/tts_end_of_speech.toml: espeak says commands of the robot's grammar, behind the
    # gate, then with the driver's room sound after; then a command with a pause inside, and a word
    # in free speech. Each text's utterance ends at its last block (the block where the end was heard).
    scenario = load_scenario(str(ROOT / "scenarios" / "tts_end_of_speech.toml"), SpeechEventConfig())
    pause = scenario.config.speech_pause_period
    timed = {}
    for end_of_speech in (0.3, 0.0):
        config = dataclasses.replace(scenario.config, end_of_speech=end_of_speech)
        outcome = run_in_memory(dataclasses.replace(scenario, config=config))
        ends = [message.last_block for message in outcome.transcripts if message.final]
        timed[end_of_speech] = [(round(p.time - end, 6), p.text) for p, end in zip(outcome.published, ends)]
    assert timed[0.0] == [
        (pause, "go to the kitchen"),
        (pause, "what time is it"),
        (pause, "go to the kitchen"),
        (pause, "hello"),
    ]
    assert timed[0.3] == [
        (0.3, "go to the kitchen"),  # the gate: no block for end_of_speech
        (0.0, "what time is it"),  # heard in the room sound, decided as the block came
        (pause, "go to the kitchen"),  # "go to" was decided (no phrase): the pause ends it
        (pause, "hello"),  # free speech: pocketsphinx does not decide
    ]


# end_of_speech and speculation_gap left to their defaults: on in grammar mode, off in free speech.
DEFAULT = dataclasses.replace(AT_16K, partial_period=0.0, health_check_period=1.0)


def test_left_to_its_default_the_end_of_speech_ends_the_turn_in_grammar_mode() -> None:
    assert DEFAULT.end_of_speech is None and DEFAULT.speculation_gap is None
    gated = _speech("stop")  # blocks that stop with the speech, as the robot's gate sends them
    last_block = _last_block(gated)
    assert _timed(_run(DEFAULT, gated)) == [(round(last_block + GRAMMAR_END_OF_SPEECH, 6), "stop")]
    # The driver's room sound after the speech: the end heard in it, long before the pause.
    room = _speech("stop", 1.0)
    ended = _run(DEFAULT, room)
    assert ended.texts() == ["stop"] and ended.published[0][0] < _last_block(room)


def test_left_to_its_default_an_engine_that_cannot_be_stopped_waits_for_the_pause_in_grammar_mode() -> None:
    # pocketsphinx's grammar takes a piece of speech cut at a pause for the nearest phrase: set,
    # end_of_speech decides with it (the tests above); left to its default, it does not.
    for said in (_speech("stop"), _speech("stop", 1.0)):
        last_block = _last_block(said)
        rig = _run(DEFAULT, said, engine=CannotBeStopped)
        assert _timed(rig) == [(round(last_block + DEFAULT.speech_pause_period, 6), "stop")]
        assert rig.node.speculations.started == 0


@pytest.mark.parametrize("engine", ENGINES, ids=lambda engine: engine.__name__)
def test_left_to_its_default_the_end_of_speech_does_not_end_a_turn_in_free_speech(engine: Engine) -> None:
    # "yes" is a complete answer: with end_of_speech set, the engine that can be stopped ends the turn.
    audio = _speech("yes", 1.0)
    last_block = _last_block(audio)
    assert _timed(_run(DEFAULT, audio, grammar="", engine=engine)) == [
        (round(last_block + DEFAULT.speech_pause_period, 6), "yes")
    ]
    if engine is ToneRecognizer:
        set_to_it = _run(dataclasses.replace(DEFAULT, end_of_speech=GRAMMAR_END_OF_SPEECH), audio, grammar="")
        assert set_to_it.published[0][0] < last_block


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.tuples(st.sampled_from(WORDS), st.floats(0.0, 1.2)), min_size=1, max_size=4),
    st.floats(0.0, 2.5),
    # Where the default does not decide: free speech, and an engine that cannot be stopped.
    st.sampled_from([("", ToneRecognizer), ("", CannotBeStopped), (COMMANDS, CannotBeStopped)]),
    # speculation_gap left empty, shorter and longer than end_of_speech's 0.3, and none at all
    st.sampled_from([None, 0.1, 0.5, 2.0]),
)
def test_left_to_its_default_free_speech_and_pocketsphinx_are_as_with_end_of_speech_off(
    turns: List[Tuple[str, float]], job_seconds: float, mode: Tuple[str, Engine], gap: Optional[float]
) -> None:
    # The same texts at the same times, and the same speculations: none on the audio up to an end.
    grammar, engine = mode
    config = dataclasses.replace(DEFAULT, speculation_gap=gap)
    default = _spoken_with_gaps(config, turns, grammar, job_seconds, engine)
    off = _spoken_with_gaps(
        dataclasses.replace(config, end_of_speech=0.0), turns, grammar, job_seconds, engine
    )
    assert _timed(default) == _timed(off)
    assert default.node.speculations.started == off.node.speculations.started


def test_left_to_its_default_a_grammar_set_and_cleared_at_run_time_turns_the_end_of_speech_on_and_off() -> (
    None
):
    rig = Rig(DEFAULT, ToneRecognizer())
    said = _speech("yes", 1.0)
    turn = _last_block(said) + DEFAULT.speech_pause_period + 0.5
    for grammar in ("yes|no", "", "yes|no"):
        assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(grammar)).response == 1  # type: ignore[attr-defined]
        start = rig.clock.now()
        rig.speak(said, BLOCK)
        rig.clock.advance(turn - (rig.clock.now() - start))
    after_start = [round(when - start, 6) for (when, _), start in zip(rig.published, (0.0, turn, 2 * turn))]
    assert rig.texts() == ["yes", "yes", "yes"]
    last_block = _last_block(said)
    assert after_start[0] < last_block and after_start[2] < last_block
    assert after_start[1] == round(last_block + DEFAULT.speech_pause_period, 6)


def test_left_to_its_default_the_speculation_starts_sooner_while_a_grammar_set_at_run_time_is_in_force() -> (
    None
):
    # Blocks that stop with the speech, an engine that takes 0.15 s: speculating 0.1 s after the
    # last block, its text is ready when the end is heard (0.3 s); at 0.3 s it would come at 0.45.
    audio = _speech("stop")
    last_block = _last_block(audio)
    rig = _run(DEFAULT, audio, job_seconds=0.15)  # the grammar is set by set_grammar
    assert _timed(rig) == [(round(last_block + GRAMMAR_END_OF_SPEECH, 6), "stop")]
    assert rig.node.speculations.started == 1


SLOW = 3.0  # seconds an engine takes to decide: longer than the pause (a slow or busy machine)


@pytest.mark.parametrize("job_seconds", [0.0, SLOW])
def test_a_call_after_the_pause_applies_to_the_next_utterance_however_long_the_decision_takes(
    job_seconds: float,
) -> None:
    # The robot's controller clears the grammar once the answer's pause is over. With a fast
    # engine the end of speech decided 'maybe' long before; with a slow one the decision was still
    # pending at the call, and the utterance once ended after it, in free speech: 'maybe' published.
    audio = _speech("maybe")
    rig = Rig(DEFAULT, ToneRecognizer(), job_seconds=job_seconds)
    assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest("yes|no")).response == 1  # type: ignore[attr-defined]
    rig.speak(audio, BLOCK)
    rig.clock.advance(DEFAULT.speech_pause_period + 0.5)
    assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest("")).response == 1  # type: ignore[attr-defined]
    rig.speak(_speech("thank you"), BLOCK)
    rig.clock.advance(DEFAULT.speech_pause_period + 4 * SLOW)
    assert rig.texts() == ["thank you"]


@pytest.mark.parametrize("job_seconds", [0.0, SLOW])
def test_an_answer_whose_pause_is_over_is_published_though_the_node_is_disabled_before_its_decision(
    job_seconds: float,
) -> None:
    rig = Rig(DEFAULT, ToneRecognizer(), job_seconds=job_seconds)
    assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest("yes|no")).response == 1  # type: ignore[attr-defined]
    rig.speak(_speech("yes"), BLOCK)
    rig.clock.advance(DEFAULT.speech_pause_period + 0.5)
    assert rig.bus.call(SET_ENABLED_SERVICE, SetEnabledRequest("false")).response == 1  # type: ignore[attr-defined]
    rig.clock.advance(DEFAULT.speech_pause_period + 4 * SLOW)
    assert rig.texts() == ["yes"]
