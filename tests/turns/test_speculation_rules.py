"""The speculation rules alone (speech_event/turns/speculation.py): Speculation and SpeculationRules."""

import dataclasses
from typing import List, NamedTuple, Optional, Tuple

import numpy as np
import pytest

from fixtures.fakes import SpyRecognizer, StoppableRecognizer
from speech_event.config import SpeechEventConfig
from speech_event.grammar import Grammar, requested_grammar
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome
from speech_event.pipeline.screen import Discard
from speech_event.ports import Recognizer, Stoppable, Transcript
from speech_event.turns.speculation import (
    Speculation,
    SpeculationCounts,
    SpeculationRules,
    decides_at_end_of_speech,
    is_complete,
)

CONFIG = SpeechEventConfig(speculative_recognition=True, complete_answers="yes,no")
NO_ANSWERS = dataclasses.replace(CONFIG, complete_answers="")


COMMANDS = requested_grammar("go to the kitchen|stop")


class Handle:
    """The executor's handle of a submitted speculation; counts the cancels."""

    def __init__(self) -> None:
        self.cancels = 0

    def cancel(self) -> None:
        self.cancels += 1


class Timer:
    def __init__(self) -> None:
        self.cancels = 0

    def cancel(self) -> None:
        self.cancels += 1


def _job(
    samples: int, recognizer: Recognizer, number: int = 1, grammar: Optional[Grammar] = None
) -> RecognitionJob:
    return RecognitionJob(
        number,
        0.0,
        1.0,
        0.5,
        np.zeros(samples, dtype=np.float32),
        recognizer,
        "english",
        samples / 16000,
        grammar,
    )


def _said(text: str, took: float = 0.25) -> RecognitionOutcome:
    return RecognitionOutcome(Transcript(text), took=took)


def _speculating(running: bool = True) -> Tuple[SpeculationRules, StoppableRecognizer, Speculation]:
    """Rules under CONFIG with one speculation started on 4096 samples of a stoppable engine;
    ``running``: the worker has started it."""
    rules = SpeculationRules(CONFIG)
    engine = StoppableRecognizer()
    speculation = rules.start(4096, engine, None)
    speculation.running = running
    return rules, engine, speculation


def test_the_fakes_have_the_abilities_they_are_named_for() -> None:
    assert isinstance(StoppableRecognizer(), Stoppable)
    assert not isinstance(SpyRecognizer(), Stoppable)


# -- may_start and start ----------------------------------------------------------------------------


def test_a_stoppable_engine_may_speculate_while_the_worker_is_idle() -> None:
    assert SpeculationRules(CONFIG).may_start(StoppableRecognizer(), worker_idle=True)


def test_an_engine_that_cannot_be_stopped_speculates_only_on_the_audio_up_to_the_end_of_speech() -> None:
    rules = SpeculationRules(CONFIG)
    assert not rules.may_start(SpyRecognizer(), worker_idle=True)
    assert rules.may_start(SpyRecognizer(), worker_idle=True, at_end_of_speech=True)
    assert not rules.may_start(SpyRecognizer(), worker_idle=False, at_end_of_speech=True)


def test_an_engine_that_cannot_be_stopped_decides_on_the_end_of_speech_only_with_a_grammar() -> None:
    assert decides_at_end_of_speech(StoppableRecognizer(), None, chosen=True)
    assert decides_at_end_of_speech(StoppableRecognizer(), COMMANDS, chosen=True)
    assert decides_at_end_of_speech(SpyRecognizer(), COMMANDS, chosen=True)
    assert not decides_at_end_of_speech(SpyRecognizer(), None, chosen=True)


def test_end_of_speech_left_to_its_default_decides_only_with_a_grammar_and_an_engine_that_can_be_stopped() -> (
    None
):
    assert decides_at_end_of_speech(StoppableRecognizer(), COMMANDS, chosen=False)
    assert not decides_at_end_of_speech(SpyRecognizer(), COMMANDS, chosen=False)
    assert not decides_at_end_of_speech(StoppableRecognizer(), None, chosen=False)
    assert not decides_at_end_of_speech(SpyRecognizer(), None, chosen=False)


def test_no_speculation_while_the_worker_is_busy() -> None:
    assert not SpeculationRules(CONFIG).may_start(StoppableRecognizer(), worker_idle=False)


def test_no_speculation_while_another_one_is_there() -> None:
    rules = SpeculationRules(CONFIG)
    engine = StoppableRecognizer()
    rules.start(4096, engine, None)
    assert not rules.may_start(engine, worker_idle=True)


def test_no_speculation_when_speculative_recognition_is_off() -> None:
    rules = SpeculationRules(dataclasses.replace(CONFIG, speculative_recognition=False))
    assert not rules.may_start(StoppableRecognizer(), worker_idle=True)


def test_start_makes_the_current_speculation_and_counts_it() -> None:
    rules = SpeculationRules(CONFIG)
    engine = StoppableRecognizer()
    speculation = rules.start(4096, engine, None)
    assert rules.current is speculation
    assert (speculation.samples, speculation.recognizer) == (4096, engine)
    assert (speculation.running, speculation.cancelled) == (False, False)
    assert (speculation.handle, speculation.outcome, speculation.adopted, speculation.watchdog) == (
        None,
        None,
        None,
        None,
    )
    assert rules.counts == SpeculationCounts(started=1, used=0, wasted_seconds=0.0)


# -- Speculation ----------------------------------------------------------------------------------


def test_a_speculation_is_for_exactly_its_audio_engine_and_grammar() -> None:
    engine = StoppableRecognizer()
    speculation = Speculation(4096, engine, COMMANDS)
    assert speculation.is_for(_job(4096, engine, grammar=COMMANDS))
    assert speculation.is_for(_job(4096, engine, grammar=requested_grammar("go to the kitchen|stop")))
    assert not speculation.is_for(_job(4097, engine, grammar=COMMANDS))
    assert not speculation.is_for(_job(4096, StoppableRecognizer(), grammar=COMMANDS))
    assert not speculation.is_for(_job(4096, engine, grammar=None))
    assert not speculation.is_for(_job(4096, engine, grammar=requested_grammar("yes|no")))


def test_a_cancelled_speculation_is_for_nothing() -> None:
    engine = StoppableRecognizer()
    speculation = Speculation(4096, engine, None)
    speculation.cancel()
    assert not speculation.is_for(_job(4096, engine))


def test_cancelling_a_speculation_not_yet_run_cancels_its_job_and_stops_no_engine() -> None:
    engine = StoppableRecognizer()
    speculation = Speculation(4096, engine, None)
    speculation.handle = handle = Handle()
    speculation.cancel()
    assert speculation.cancelled
    assert handle.cancels == 1
    assert engine.stops == 0


def test_cancelling_a_running_speculation_stops_its_engine() -> None:
    engine = StoppableRecognizer()
    speculation = Speculation(4096, engine, None)
    speculation.handle = handle = Handle()
    speculation.running = True
    speculation.cancel()
    assert handle.cancels == 1
    assert engine.stops == 1


def test_cancelling_a_running_speculation_on_an_engine_that_cannot_stop_lets_it_run() -> None:
    speculation = Speculation(4096, SpyRecognizer(), None)
    speculation.running = True
    speculation.cancel()
    assert speculation.cancelled


# -- drop -----------------------------------------------------------------------------------------


def test_drop_with_no_speculation_does_nothing() -> None:
    rules = SpeculationRules(CONFIG)
    rules.drop()
    assert rules.current is None
    assert rules.counts == SpeculationCounts()


def test_drop_cancels_a_running_speculation_and_stops_its_engine() -> None:
    rules, engine, speculation = _speculating()
    speculation.handle = handle = Handle()
    rules.drop()
    assert rules.current is None
    assert speculation.cancelled
    assert (handle.cancels, engine.stops) == (1, 1)
    assert rules.counts.wasted_seconds == 0.0  # counted when it ends (finished)


def test_drop_of_a_finished_speculation_counts_its_engine_time_as_wasted() -> None:
    rules, engine, speculation = _speculating()
    assert rules.finished(speculation, _said("go", took=0.75)) is None
    rules.drop()
    assert rules.current is None
    assert engine.stops == 0  # it no longer runs
    assert rules.counts == SpeculationCounts(started=1, used=0, wasted_seconds=0.75)


def test_drop_leaves_an_adopted_speculation_alone() -> None:
    rules, engine, speculation = _speculating()
    assert rules.adopt(_job(4096, engine)) is speculation
    rules.drop()
    assert rules.current is speculation
    assert not speculation.cancelled
    assert engine.stops == 0


# -- adopt ----------------------------------------------------------------------------------------


def test_adopt_with_no_speculation_is_none() -> None:
    assert SpeculationRules(CONFIG).adopt(_job(4096, StoppableRecognizer())) is None


def test_a_closed_utterance_adopts_the_running_speculation_on_its_audio() -> None:
    rules, engine, speculation = _speculating()
    job = _job(4096, engine)
    assert rules.adopt(job) is speculation
    assert speculation.adopted is job
    assert rules.current is speculation  # still running: it is still the one
    assert rules.counts == SpeculationCounts(started=1, used=0)
    assert rules.running_for(job)


def test_a_closed_utterance_adopts_a_finished_speculation_and_it_is_used() -> None:
    rules, engine, speculation = _speculating(running=False)
    outcome = _said("go left")
    assert rules.finished(speculation, outcome) is None  # the utterance was still being collected
    job = _job(4096, engine)
    assert rules.adopt(job) is speculation
    assert speculation.outcome is outcome
    assert rules.current is None
    assert rules.counts == SpeculationCounts(started=1, used=1)
    assert not rules.running_for(job)


def test_a_closed_utterance_of_other_audio_drops_the_speculation() -> None:
    rules, engine, speculation = _speculating()
    speculation.handle = handle = Handle()
    assert rules.adopt(_job(8192, engine)) is None
    assert rules.current is None
    assert speculation.cancelled
    assert speculation.adopted is None
    assert (handle.cancels, engine.stops) == (1, 1)


def test_a_closed_utterance_bound_to_another_engine_drops_the_speculation() -> None:
    rules, _, speculation = _speculating(running=False)
    assert rules.adopt(_job(4096, StoppableRecognizer())) is None
    assert rules.current is None
    assert speculation.cancelled


def test_a_finished_speculation_on_other_audio_is_wasted() -> None:
    rules, engine, speculation = _speculating(running=False)
    rules.finished(speculation, _said("go", took=0.5))
    assert rules.adopt(_job(8192, engine)) is None
    assert rules.counts == SpeculationCounts(started=1, used=0, wasted_seconds=0.5)


def test_a_second_closed_utterance_does_not_adopt_an_adopted_speculation() -> None:
    rules, engine, speculation = _speculating()
    first = _job(4096, engine, number=1)
    rules.adopt(first)
    assert rules.adopt(_job(4096, engine, number=2)) is None
    assert speculation.adopted is first
    assert rules.current is speculation
    assert not speculation.cancelled


# -- finished -------------------------------------------------------------------------------------


def test_an_adopted_speculation_that_finishes_gives_its_utterance() -> None:
    rules, engine, speculation = _speculating()
    job = _job(4096, engine)
    rules.adopt(job)
    outcome = _said("go left")
    assert rules.finished(speculation, outcome) is job
    assert speculation.outcome is outcome
    assert not speculation.running
    assert rules.current is None
    assert rules.counts == SpeculationCounts(started=1, used=1, wasted_seconds=0.0)


def test_a_speculation_that_finishes_while_its_utterance_is_collected_keeps_its_outcome() -> None:
    rules, _, speculation = _speculating()
    outcome = _said("go")
    assert rules.finished(speculation, outcome) is None
    assert speculation.outcome is outcome
    assert not speculation.running
    assert rules.current is speculation
    assert rules.counts == SpeculationCounts(started=1)


def test_a_cancelled_speculation_that_finishes_is_wasted_engine_time() -> None:
    rules, _, speculation = _speculating()
    rules.drop()
    assert rules.finished(speculation, _said("go", took=1.25)) is None
    assert speculation.outcome is None
    assert not speculation.running
    assert rules.counts == SpeculationCounts(started=1, used=0, wasted_seconds=1.25)


def test_wasted_engine_time_adds_up() -> None:
    rules = SpeculationRules(CONFIG)
    engine = StoppableRecognizer()
    for took in (0.25, 0.5):
        speculation = rules.start(4096, engine, None)
        speculation.running = True
        rules.drop()
        rules.finished(speculation, _said("go", took=took))
    assert rules.counts == SpeculationCounts(started=2, used=0, wasted_seconds=0.75)


def test_finished_cancels_the_watchdog_of_an_adopted_speculation() -> None:
    rules, engine, speculation = _speculating()
    rules.adopt(_job(4096, engine))
    speculation.watchdog = watchdog = Timer()
    rules.finished(speculation, _said("go"))
    assert watchdog.cancels == 1


def test_running_for_is_false_for_another_job_or_a_speculation_not_running() -> None:
    rules, engine, speculation = _speculating(running=False)
    job = _job(4096, engine)
    assert not rules.running_for(job)  # not adopted
    rules.adopt(job)
    assert not rules.running_for(job)  # adopted, not started on the worker
    speculation.running = True
    assert rules.running_for(job)
    assert not rules.running_for(_job(4096, engine, number=2))


# -- ends_turn ------------------------------------------------------------------------------------


def _speculate(
    rules: SpeculationRules,
    engine: Recognizer,
    outcome: RecognitionOutcome,
    grammar: Optional[Grammar] = None,
) -> bool:
    """Whether a speculation that ran to its end while its utterance was still being collected
    ends the turn; then the next block drops it, as in the node."""
    speculation = rules.start(4096, engine, grammar)
    speculation.running = True
    assert rules.finished(speculation, outcome) is None
    ends = rules.ends_turn(speculation)
    rules.drop()
    return ends


class Said(NamedTuple):
    """The texts of the speculations on one utterance, each with whether it ends the turn, with
    ``grammar`` in force (None: free speech)."""

    config: SpeechEventConfig
    grammar: Optional[Grammar]
    texts: List[Tuple[str, bool]]


ENDS_TURN = {
    "one_of_complete_answers_ends_the_turn_in_any_case_and_spacing": Said(CONFIG, None, [(" Yes ", True)]),
    "a_text_not_among_complete_answers_does_not_end_the_turn_the_first_time": Said(
        CONFIG, None, [("go left", False)]
    ),
    "the_same_text_twice_on_one_utterance_ends_the_turn": Said(
        NO_ANSWERS, None, [("go left", False), ("go left", True)]
    ),
    "a_different_text_the_second_time_does_not_end_the_turn": Said(
        NO_ANSWERS, None, [("go", False), ("go left", False), ("go left", True)]
    ),
    "the_same_capitalised_text_twice_ends_the_turn": Said(
        NO_ANSWERS, None, [("Go left", False), ("Go left", True)]
    ),
    "a_sentence_the_engine_closes_ends_the_turn": Said(
        NO_ANSWERS, None, [("Go left.", True), ("Where am I?", True), ("Stop!", True)]
    ),
    "a_sentence_left_open_or_trailing_off_does_not": Said(
        NO_ANSWERS,
        None,
        [("Go to the", False), ("Go to the...", False), ("Go to\u2026", False), (" . ", False)],
    ),
    "an_empty_text_never_ends_the_turn_even_twice_or_in_grammar_mode": Said(
        NO_ANSWERS, COMMANDS, [("  ", False), ("  ", False)]
    ),
    "with_a_grammar_in_force_any_text_ends_the_turn": Said(
        NO_ANSWERS, COMMANDS, [("go to the kitchen", True)]
    ),
}


@pytest.mark.parametrize("said", list(ENDS_TURN.values()), ids=list(ENDS_TURN))
def test_whether_a_speculations_text_ends_the_turn(said: Said) -> None:
    rules = SpeculationRules(said.config)
    engine = StoppableRecognizer()
    assert [
        (text, _speculate(rules, engine, _said(text), said.grammar)) for text, _ in said.texts
    ] == said.texts


def test_is_complete_compares_the_previous_text_as_given() -> None:
    """The cause of the failure the_same_capitalised_text_twice_ends_the_turn (above) found: the
    previous text is not normalised like the new one."""
    assert not is_complete("Go left", "Go left", False, frozenset())
    assert is_complete("Go left", "go left", False, frozenset())


def test_texts_of_the_utterance_before_are_forgotten() -> None:
    rules = SpeculationRules(NO_ANSWERS)
    engine = StoppableRecognizer()
    assert not _speculate(rules, engine, _said("go left"))
    rules.new_utterance()
    assert not _speculate(rules, engine, _said("go left"))


def test_a_failed_or_discarded_speculation_does_not_end_the_turn_and_resets_the_comparison() -> None:
    rules = SpeculationRules(NO_ANSWERS)
    engine = StoppableRecognizer()
    assert not _speculate(rules, engine, _said("go left"))
    failed = RecognitionOutcome(error=RuntimeError("stopped"))
    assert not _speculate(rules, engine, failed)
    assert not _speculate(rules, engine, _said("go left"))
    assert not _speculate(rules, engine, RecognitionOutcome(discard=Discard.TOO_SHORT))


def test_a_cancelled_adopted_or_unfinished_speculation_does_not_end_the_turn() -> None:
    rules = SpeculationRules(CONFIG)
    engine = StoppableRecognizer()
    unfinished = rules.start(4096, engine, None)
    assert not rules.ends_turn(unfinished)
    adopted = unfinished
    adopted.outcome = _said("yes")
    adopted.adopted = _job(4096, engine)
    assert not rules.ends_turn(adopted)
    cancelled = Speculation(4096, engine, None)
    cancelled.outcome = _said("yes")
    cancelled.cancel()
    assert not rules.ends_turn(cancelled)


def test_a_speculation_that_does_not_count_leaves_the_comparison_as_it_was() -> None:
    rules = SpeculationRules(NO_ANSWERS)
    engine = StoppableRecognizer()
    assert not _speculate(rules, engine, _said("go left"))
    cancelled = Speculation(4096, engine, None)
    cancelled.outcome = _said("turn right")
    cancelled.cancel()
    assert not rules.ends_turn(cancelled)
    assert _speculate(rules, engine, _said("go left"))


def test_counts_start_at_zero() -> None:
    assert SpeculationRules(CONFIG).counts == SpeculationCounts(started=0, used=0, wasted_seconds=0.0)


@pytest.mark.parametrize(
    ("text", "grammar", "by_text", "by_audio_alone"),
    [
        ("Go to the", None, False, True),
        ("Go to the kitchen.", None, True, True),
        ("", None, False, False),
        ("go to the kitchen", COMMANDS, True, True),
    ],
)
def test_with_the_audio_alone_deciding_any_text_of_free_speech_is_complete_for_the_model_to_judge(
    text: str, grammar: Optional[Grammar], by_text: bool, by_audio_alone: bool
) -> None:
    outcome = RecognitionOutcome(Transcript(text, None))
    heard = dataclasses.replace(CONFIG, turn_end_model="smart-turn")
    audio_alone = dataclasses.replace(heard, turn_end_text=False)
    # (configuration, whether the turn-end model hears the speculation, complete): it hears only in
    # free speech (BackgroundRuns), and with auto only where it hears the engine and language in force
    for config, hears, complete in (
        (CONFIG, False, by_text),
        (heard, grammar is None, by_text),
        (audio_alone, grammar is None, by_audio_alone),
        (audio_alone, False, by_text),
    ):
        speculation = Speculation(16000, StoppableRecognizer(), grammar)
        speculation.hears_turn_end = hears
        assert SpeculationRules(config).text_complete(speculation, outcome) == complete
        rules = SpeculationRules(config)
        started = rules.start(16000, StoppableRecognizer(), grammar)
        started.hears_turn_end = hears
        rules.finished(started, outcome, heard_complete=False)
        assert not started.complete  # the audio says the turn goes on
        rules = SpeculationRules(config)
        started = rules.start(16000, StoppableRecognizer(), grammar)
        started.hears_turn_end = hears
        rules.finished(started, outcome, heard_complete=True)
        assert started.complete == complete


def test_in_free_speech_a_stoppable_engine_decides_at_the_end_of_speech_where_a_turn_end_model_hears() -> (
    None
):
    assert decides_at_end_of_speech(StoppableRecognizer(), None, chosen=False, hears_turn_end=True)
    assert not decides_at_end_of_speech(SpyRecognizer(), None, chosen=False, hears_turn_end=True)
    # in grammar mode the model changes nothing: pocketsphinx still decides only when chosen
    assert not decides_at_end_of_speech(SpyRecognizer(), COMMANDS, chosen=False, hears_turn_end=True)


@pytest.mark.parametrize(
    ("text", "grammar", "needed"),
    [
        ("Go to the kitchen.", None, True),  # a closed sentence: the audio must agree
        ("Yes.", None, False),  # one of complete_answers ends the turn at once
        ("no", None, False),
        ("Go to the", None, False),  # the text is not complete: the turn cannot end anyway
        ("go to the kitchen", COMMANDS, False),  # a grammar's phrase decides alone
    ],
)
def test_the_turn_end_model_is_asked_only_where_a_complete_text_of_free_speech_is_no_answer(
    text: str, grammar: Optional[Grammar], needed: bool
) -> None:
    rules = SpeculationRules(dataclasses.replace(CONFIG, turn_end_model="smart-turn"))
    speculation = Speculation(16000, StoppableRecognizer(), grammar)
    assert rules.needs_the_audio(speculation, RecognitionOutcome(Transcript(text, None))) == needed
