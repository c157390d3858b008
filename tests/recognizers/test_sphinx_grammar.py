"""pocketsphinx in grammar mode: the phrase said is published, speech outside the grammar is not
(issue 19), on real recordings (Debian's pocketsphinx-testdata) and the tts voice."""

from typing import Any, Iterator, List, Tuple

import numpy as np
import pytest

from fixtures import recordings
from fixtures.festival import festival_voice
from fixtures.paths import ROOT
from fixtures.tts import speak_tts
from speech_event.errors import GrammarError, ModelError
from speech_event.grammar import Grammar, jsgf_grammar, load_grammar, phrases_grammar, requested_grammar
from speech_event.ports import Grammars, Transcript
from speech_event.recognizers.sphinx import DEFAULT_GRAMMAR_THRESHOLD, SphinxRecognizer

COMMANDS = ROOT / "harness" / "data" / "robot_commands.txt"


def _commands() -> List[str]:
    return [line for line in COMMANDS.read_text().splitlines() if line and not line.startswith("#")]


@pytest.fixture(scope="module")
def commands() -> SphinxRecognizer:
    return SphinxRecognizer(load_grammar(COMMANDS))


@pytest.fixture(scope="module")
def cards() -> SphinxRecognizer:
    return SphinxRecognizer(load_grammar(recordings.CARDS_GRAMMAR))


def test_the_engine_takes_grammars(commands: SphinxRecognizer) -> None:
    assert isinstance(commands, Grammars)


def test_every_cards_recording_gives_exactly_its_transcription(cards: SphinxRecognizer) -> None:
    # cards.gram has 1.4 million sentences: pocketsphinx searches the JSGF itself
    expected = recordings.cards()
    heard = [(recording.name, cards.transcribe(recording.samples())) for recording in expected]
    assert heard == [(recording.name, Transcript(recording.text)) for recording in expected]


def test_every_librivox_recording_is_rejected_naming_the_nearest_cards(cards: SphinxRecognizer) -> None:
    librivox = recordings.librivox()
    assert len(librivox) == 5
    for recording in librivox:
        transcript = cards.transcribe(recording.samples())
        assert transcript.text == ""
        assert transcript.rejected, recording.name
        assert cards.last_ratio is not None and cards.last_ratio < DEFAULT_GRAMMAR_THRESHOLD


def test_every_robot_command_in_the_tts_voice_is_published(commands: SphinxRecognizer) -> None:
    said = _commands()
    assert len(said) == 32
    assert [commands.transcribe(speak_tts(command, 16000)) for command in said] == [
        Transcript(command) for command in said
    ]


@pytest.mark.parametrize(
    ("sentence", "nearest"),
    [
        ("go to the kitchen later", "go to the kitchen"),
        ("bring me the red book", "bring me the red cup"),
        ("open the box", "open the door"),
        ("dance with me", "dance"),
        ("the kitchen is dirty", "what is your name"),
        ("please open the window", "open the door"),
        ("turn left at the corner", "open the door"),
    ],
)
def test_a_near_miss_is_rejected_naming_the_nearest_command(
    commands: SphinxRecognizer, sentence: str, nearest: str
) -> None:
    assert commands.transcribe(speak_tts(sentence, 16000)) == Transcript("", rejected=nearest)


@pytest.mark.parametrize(
    ("voice", "said", "published"),
    [
        # pruned within its first word by pocketsphinx's default beams: "thank you", 381 nats less likely
        ("slt", "come here", Transcript("come here")),
        ("kal", "come here", Transcript("come here")),  # -95 nats: within the default threshold
        ("kal", "bring me the red book", Transcript("", rejected="bring me the red cup")),  # -106: beyond it
    ],
)
def test_in_festivals_voices_commands_are_published_and_a_near_miss_is_not(
    commands: SphinxRecognizer, voice: str, said: str, published: Transcript
) -> None:
    """Issue 32: the grammars' wider beams and the default threshold, -100 nats (sphinx.py)."""
    assert commands.transcribe(festival_voice(voice)(said, 16000)) == published


def test_speech_reaching_no_whole_phrase_names_the_partial_path(commands: SphinxRecognizer) -> None:
    # No path of "go to" reaches the grammar's end: nothing judged, the partial path named.
    assert commands.transcribe(speak_tts("go to", 16000)) == Transcript("", rejected="go to")
    assert commands.last_ratio is None


def test_too_short_for_any_path_gives_nothing(commands: SphinxRecognizer) -> None:
    assert commands.transcribe(np.zeros(100, np.float32)) == Transcript("")


def test_the_threshold_is_honoured() -> None:
    grammar = load_grammar(COMMANDS)
    near_miss = speak_tts("go to the kitchen later", 16000)
    lenient = SphinxRecognizer(grammar, grammar_threshold=-1e9)
    assert lenient.transcribe(near_miss) == Transcript("go to the kitchen")
    judged = lenient.last_ratio
    assert judged is not None and judged < DEFAULT_GRAMMAR_THRESHOLD
    just_above = SphinxRecognizer(grammar, grammar_threshold=judged + 1.0)
    assert just_above.transcribe(near_miss) == Transcript("", rejected="go to the kitchen")
    at = SphinxRecognizer(grammar, grammar_threshold=judged)
    assert at.transcribe(near_miss) == Transcript("go to the kitchen")
    strict = SphinxRecognizer(grammar, grammar_threshold=1e9)
    assert strict.transcribe(speak_tts("go to the kitchen", 16000)) == Transcript(
        "", rejected="go to the kitchen"
    )


def test_without_rejection_the_nearest_phrase_is_published_as_pocketsphinx_finds_it() -> None:
    recognizer = SphinxRecognizer(load_grammar(COMMANDS), grammar_threshold=-float("inf"))
    assert recognizer.transcribe(speak_tts("please open the window", 16000)) == Transcript("open the door")
    assert recognizer.last_ratio is None


def test_a_grammar_word_missing_from_the_dictionary_is_named() -> None:
    recognizer = SphinxRecognizer()
    with pytest.raises(GrammarError) as error:
        recognizer.check_grammar(phrases_grammar(["go to the kitchen", "muraho pepper"], "robot.txt"))
    assert str(error.value) == "robot.txt: words not in pocketsphinx's English dictionary: muraho"
    with pytest.raises(GrammarError) as error:
        SphinxRecognizer(phrases_grammar(["muraho", "yes"], "answers.txt"))
    assert str(error.value) == "answers.txt: words not in pocketsphinx's English dictionary: muraho"


def test_words_of_an_endless_jsgf_grammar_are_checked_without_its_tags_weights_and_comments() -> None:
    grammar = jsgf_grammar(
        "#JSGF V1.0;\ngrammar g;\n/* a comment; with = signs and words */\n"
        "public <s> = ( /2.0/ go {forward} | muraho | <more> )+ ; // yet another comment\n"
        "<more> = zzyzx [ please ];\n",
        "g.jsgf",
    )
    assert grammar.phrases is None  # endless: the words come from the JSGF itself
    with pytest.raises(GrammarError) as error:
        SphinxRecognizer().check_grammar(grammar)
    assert str(error.value) == "g.jsgf: words not in pocketsphinx's English dictionary: muraho, zzyzx"


def test_a_jsgf_grammar_is_used_as_it_is() -> None:
    answers = jsgf_grammar("#JSGF V1.0;\ngrammar answers;\npublic <answer> = yes | no;\n", "answers.jsgf")
    assert SphinxRecognizer(answers).transcribe(speak_tts("no", 16000)) == Transcript("no")


def test_a_grammar_cannot_be_used_with_a_keyword_list() -> None:
    recognizer = SphinxRecognizer(keywords=str(ROOT / "config" / "robot_keywords.txt"))
    grammar = load_grammar(COMMANDS)
    with pytest.raises(GrammarError) as error:
        recognizer.check_grammar(grammar)
    assert str(error.value) == (
        f"{COMMANDS}: a keyword list (pocketsphinx_keywords) is in force; pocketsphinx decodes with a "
        "grammar or a keyword list, not both"
    )
    with pytest.raises(ModelError) as refused:
        SphinxRecognizer(grammar, keywords=str(ROOT / "config" / "robot_keywords.txt"))
    assert str(refused.value) == "set grammar or pocketsphinx_keywords, not both"


class _CountingDecoder:
    """The decoder, counting the grammars compiled into it."""

    def __init__(self, decoder: Any) -> None:
        self._decoder = decoder
        self.compiled: List[str] = []

    def add_jsgf_string(self, name: str, jsgf: str) -> None:
        self.compiled.append(name)
        self._decoder.add_jsgf_string(name, jsgf)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._decoder, name)


@pytest.fixture
def switching() -> Iterator[Tuple[SphinxRecognizer, _CountingDecoder]]:
    recognizer = SphinxRecognizer()
    counting = _CountingDecoder(recognizer._grammars())
    recognizer._grammar_decoder = counting
    yield recognizer, counting


def test_use_grammar_switches_and_none_is_the_language_model_again(
    switching: Tuple[SphinxRecognizer, _CountingDecoder],
) -> None:
    recognizer, _ = switching
    free_speech = speak_tts("the weather is lovely today", 16000)
    heard_freely = SphinxRecognizer().transcribe(free_speech)
    assert heard_freely == Transcript("the weather is lovely today")
    yes_no = requested_grammar("yes|no")
    assert yes_no is not None
    recognizer.use_grammar(yes_no)
    assert recognizer.transcribe(speak_tts("no", 16000)) == Transcript("no")
    assert recognizer.transcribe(speak_tts("go to the kitchen", 16000)) == Transcript("", rejected="no")
    recognizer.use_grammar(None)
    assert recognizer.transcribe(free_speech) == heard_freely
    assert recognizer.last_ratio is None


def test_switching_back_reuses_the_compiled_grammar(
    switching: Tuple[SphinxRecognizer, _CountingDecoder],
) -> None:
    recognizer, counting = switching
    yes_no: List[Grammar] = [g for g in (requested_grammar("yes|no"), requested_grammar("yes | no")) if g]
    robot = load_grammar(COMMANDS)
    for grammar in (yes_no[0], robot, yes_no[1], None, robot, yes_no[0]):
        recognizer.use_grammar(grammar)
    assert counting.compiled == ["grammar0", "grammar1"]  # "yes | no" is the same grammar
    assert recognizer.transcribe(speak_tts("yes", 16000)) == Transcript("yes")
    recognizer.use_grammar(robot)
    assert recognizer.transcribe(speak_tts("turn left", 16000)) == Transcript("turn left")


def test_check_grammar_switches_nothing(switching: Tuple[SphinxRecognizer, _CountingDecoder]) -> None:
    recognizer, counting = switching
    yes_no = requested_grammar("yes|no")
    assert yes_no is not None
    recognizer.use_grammar(yes_no)
    recognizer.check_grammar(load_grammar(COMMANDS))
    assert counting.compiled == ["grammar0"]
    assert recognizer.transcribe(speak_tts("yes", 16000)) == Transcript("yes")
