"""Command grammars (speech_event/grammar.py): files, requests and JSGF expansion."""

from pathlib import Path

import pytest

from fixtures.paths import ROOT
from speech_event.errors import GrammarError, ModelError
from speech_event.grammar import MAX_SENTENCES, jsgf_grammar, load_grammar, phrases_grammar, requested_grammar

CARDS = Path("/usr/share/pocketsphinx/test/data/cards/cards.gram")  # Debian's pocketsphinx-testdata


def test_a_phrase_file_is_its_lines_lower_cased_without_comments_blanks_or_repeats(tmp_path: Path) -> None:
    path = tmp_path / "commands.txt"
    path.write_text("# robot commands\nGo  Left\n\nstop\ngo left\n  turn right  \n")
    grammar = load_grammar(path)
    assert grammar.phrases == ("go left", "stop", "turn right")
    assert grammar.source == str(path)
    assert grammar.jsgf == (
        "#JSGF V1.0;\ngrammar commands;\npublic <command> = ( go left ) | ( stop ) | ( turn right );\n"
    )


def test_the_robots_command_file_has_32_commands() -> None:
    grammar = load_grammar(ROOT / "harness" / "data" / "robot_commands.txt")
    assert grammar.phrases is not None and len(grammar.phrases) == 32


def test_a_jsgf_grammar_expands_to_its_sentences_from_the_first_public_rule() -> None:
    grammar = jsgf_grammar(
        "#JSGF V1.0;\ngrammar robot;\n// directions\n<dir> = left | right;\n"
        "public <move> = (turn | go) <dir> [now] {move} | /2.0/ stop;\npublic <other> = hello;\n",
        "robot.gram",
    )
    assert grammar.phrases == (
        "go left",
        "go left now",
        "go right",
        "go right now",
        "stop",
        "turn left",
        "turn left now",
        "turn right",
        "turn right now",
    )


@pytest.mark.parametrize(
    "body",
    [
        "public <many> = (a | b | c | d | e | f | g | h | i | j) (a | b | c | d | e | f | g | h | i | j) "
        "(a | b | c | d | e | f | g | h | i | j) (a | b | c);",
        "public <endless> = go <step>*;\n<step> = left | right;",
        "public <endless> = go left+;",
        "public <recursive> = go <recursive> | stop;",
    ],
)
def test_a_grammar_of_too_many_or_endless_sentences_is_for_pocketsphinx_only(body: str) -> None:
    grammar = jsgf_grammar(f"#JSGF V1.0;\ngrammar g;\n{body}\n", "g.gram")
    assert grammar.phrases is None
    with pytest.raises(GrammarError) as error:
        grammar.sentences("the NeMo engine")
    assert str(error.value) == (
        f"g.gram: more than {MAX_SENTENCES} sentences (or * and + repeats): the NeMo engine scores every "
        "sentence of a grammar; list the phrases, or use pocketsphinx"
    )


def test_the_cards_grammar_of_pocketsphinx_test_data_has_too_many_sentences_to_list() -> None:
    assert load_grammar(CARDS).phrases is None


@pytest.mark.parametrize(
    ("request_text", "phrases"),
    [
        ("yes|no", ("yes", "no")),
        (" Yes | NO |yes ", ("yes", "no")),
        ("go to the kitchen", ("go to the kitchen",)),
    ],
)
def test_a_request_of_phrases(request_text: str, phrases: tuple) -> None:  # type: ignore[type-arg]
    grammar = requested_grammar(request_text)
    assert grammar is not None and grammar.phrases == phrases and grammar.source == request_text.strip()


def test_an_empty_request_is_free_speech_and_a_file_request_loads_the_file(tmp_path: Path) -> None:
    assert requested_grammar("  ") is None
    path = tmp_path / "yes_no.txt"
    path.write_text("yes\nno\n")
    grammar = requested_grammar(str(path))
    assert grammar is not None and grammar.phrases == ("yes", "no")


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda tmp: requested_grammar(str(tmp / "missing.gram")),
            "'{tmp}/missing.gram': no such grammar file; allowed: a JSGF or phrase file, phrases parted by | "
            "(words of a-z and '), or empty for free speech",
        ),
        (
            lambda tmp: requested_grammar("yes|no way!"),
            "yes|no way!: 'no way!' has 'way!'; phrases are words of a-z and '",
        ),
        (
            lambda tmp: requested_grammar("|"),
            "|: no phrases; write one command phrase a line, or phrases parted by |",
        ),
        (
            lambda tmp: load_grammar(tmp / "none.txt"),
            "{tmp}/none.txt: cannot read the grammar: No such file or directory; allowed: a JSGF file or a "
            "file of phrases, one a line",
        ),
        (
            lambda tmp: jsgf_grammar("#JSGF V1.0;\n<a> = b;\n", "g"),
            "g: no public rule; pocketsphinx takes the first 'public <name> = ...;'",
        ),
        (
            lambda tmp: jsgf_grammar("#JSGF V1.0;\npublic <a> = <b>;\n", "g"),
            "g: rule <b> is used but not defined",
        ),
        (lambda tmp: jsgf_grammar("#JSGF V1.0;\npublic <a> = (go left;\n", "g"), "g: '(' is never closed"),
        (
            lambda tmp: jsgf_grammar("#JSGF V1.0;\npublic <a> = go 4ward;\n", "g"),
            "g: '4ward' is not a word of a-z and '",
        ),
        (
            lambda tmp: jsgf_grammar("#JSGF V1.0;\npublic a = go;\n", "g"),
            "g: cannot read 'public a = go'; a rule is <name> = expansion;",
        ),
    ],
)
def test_a_grammar_that_cannot_be_used_says_why(tmp_path: Path, make, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(GrammarError) as error:
        make(tmp_path)
    assert str(error.value) == message.format(tmp=tmp_path)
    assert isinstance(error.value, ModelError)  # stops an engine's start-up as a bad model does


def test_grammars_of_the_same_phrases_are_equal_so_engines_compile_each_once() -> None:
    assert requested_grammar("yes|no") == phrases_grammar(["yes", "no"], "yes|no")
    assert hash(requested_grammar("yes|no")) == hash(phrases_grammar(["yes", "no"], "yes|no"))


def test_a_grammars_words_are_those_of_its_sentences_even_when_they_are_too_many_to_list() -> None:
    assert requested_grammar("go left|Go right|stop").words() == ("go", "left", "right", "stop")  # type: ignore[union-attr]
    endless = jsgf_grammar(
        "#JSGF V1.0;\ngrammar g;\n/* a comment */\npublic <g> = (Go | walk) <dir>+ [now] {tag} /2/;\n"
        "<dir> = left | right;\n",
        "g.gram",
    )
    assert endless.phrases is None
    assert endless.words() == ("go", "left", "now", "right", "walk")
