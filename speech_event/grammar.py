"""Command grammars: the phrases an engine may answer with, from a file or a service request.

A grammar is a JSGF file, a text file of phrases (one a line, ``#`` starts a comment), or, in a
``set_grammar`` request, phrases separated by ``|``. Every engine decodes within it: pocketsphinx
searches the JSGF grammar itself; the NeMo and Whisper engines score each sentence of it, so a JSGF
grammar is expanded to its sentences, which must be finite and at most MAX_SENTENCES (the cards
grammar of pocketsphinx's test data, three cards in a row, has 1.4 million: pocketsphinx only).

JSGF as pocketsphinx reads it: the first public rule is the grammar; alternatives ``|``, groups
``( )``, optional ``[ ]``, rule references ``<name>``, weights ``/2.0/`` (ignored: every sentence
is allowed), tags ``{...}`` (ignored); ``*`` and ``+`` make a grammar of endless sentences.
"""

import itertools
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, FrozenSet, List, Optional, Set, Tuple

from speech_event.errors import GrammarError

MAX_SENTENCES = 2000
FREE_SPEECH = "none (free speech)"  # how logs, /diagnostics and the window say no grammar is in force
_WORD = re.compile(r"^[a-z']+$")
_TOKEN = re.compile(r"<[^<>\s]+>|/[^/]*/|\{[^}]*\}|[()\[\]|*+;=]|[^\s()\[\]|*+;=<>/{}]+")
_OPERATORS = ("(", ")", "[", "]", "|", "*", "+", "=", ";")
_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.DOTALL)

Sentences = FrozenSet[Tuple[str, ...]]


class _TooMany(Exception):
    """The expansion passed MAX_SENTENCES or repeats without end."""


@dataclass(frozen=True)
class Grammar:
    """A command grammar: where it came from, its JSGF text, and its sentences when they are few enough."""

    source: str  # the file, or the phrases as requested ("yes|no"): what logs and the window show
    jsgf: str
    # Every sentence, lower-case words parted by one space; None when more than MAX_SENTENCES or endless.
    phrases: Optional[Tuple[str, ...]]

    def words(self) -> Tuple[str, ...]:
        """Every word its sentences may use, sorted: what an engine's dictionary must hold."""
        if self.phrases is not None:
            return tuple(sorted({word for phrase in self.phrases for word in phrase.split()}))
        rules, _ = _rules(self.jsgf, self.source)
        return tuple(
            sorted({token.lower() for tokens in rules.values() for token in tokens if _is_word(token)})
        )

    def sentences(self, engine: str) -> Tuple[str, ...]:
        """The sentences, for an engine that scores each one; GrammarError when there are too many."""
        if self.phrases is None:
            raise GrammarError(
                f"{self.source}: more than {MAX_SENTENCES} sentences (or * and + repeats): {engine} scores "
                "every sentence of a grammar; list the phrases, or use pocketsphinx"
            )
        return self.phrases


def phrases_grammar(phrases: List[str], source: str) -> Grammar:
    """The grammar whose sentences are exactly ``phrases`` (case and spacing ignored)."""
    cleaned = [" ".join(phrase.lower().split()) for phrase in phrases]
    cleaned = list(dict.fromkeys(phrase for phrase in cleaned if phrase and not phrase.startswith("#")))
    if not cleaned:
        raise GrammarError(f"{source}: no phrases; write one command phrase a line, or phrases parted by |")
    for phrase in cleaned:
        bad = [word for word in phrase.split() if not _WORD.match(word)]
        if bad:
            raise GrammarError(f"{source}: {phrase!r} has {bad[0]!r}; phrases are words of a-z and '")
    alternatives = " | ".join(f"( {phrase} )" for phrase in cleaned)
    jsgf = f"#JSGF V1.0;\ngrammar commands;\npublic <command> = {alternatives};\n"
    return Grammar(source, jsgf, tuple(cleaned))


def jsgf_grammar(jsgf: str, source: str) -> Grammar:
    """A JSGF grammar, its sentences expanded when they are at most MAX_SENTENCES."""
    rules, public = _rules(jsgf, source)
    try:
        sentences = _expand(rules[public], rules, source, ())
        phrases: Optional[Tuple[str, ...]] = tuple(sorted(" ".join(sentence) for sentence in sentences))
    except _TooMany:
        phrases = None
    if phrases is not None and not [phrase for phrase in phrases if phrase]:
        raise GrammarError(f"{source}: the public rule <{public}> allows no words")
    return Grammar(source, jsgf, phrases)


def load_grammar(path: Path) -> Grammar:
    """A grammar file: JSGF when it starts with ``#JSGF``, otherwise phrases one a line."""
    try:
        content = path.read_text(encoding="utf-8")
    except OSError as problem:
        raise GrammarError(
            f"{path}: cannot read the grammar: {problem.strerror}; allowed: a JSGF file or a file "
            "of phrases, one a line"
        ) from None
    if content.lstrip().upper().startswith("#JSGF"):
        return jsgf_grammar(content, str(path))
    return phrases_grammar(content.splitlines(), str(path))


def requested_grammar(request: str) -> Optional[Grammar]:
    """What a set_grammar request asks for: None (free speech) for "", phrases parted by ``|``, or a
    file; a single phrase of words is a grammar of that phrase unless a file has that name."""
    request = request.strip()
    if not request:
        return None
    if "|" not in request and Path(request).is_file():
        return load_grammar(Path(request))
    if "|" in request or all(_WORD.match(word) for word in request.lower().split()):
        return phrases_grammar(request.split("|"), request)
    raise GrammarError(
        f"{request!r}: no such grammar file; allowed: a JSGF or phrase file, phrases parted by | "
        "(words of a-z and '), or empty for free speech"
    )


# -- JSGF -----------------------------------------------------------------------------------------


def _rules(jsgf: str, source: str) -> Tuple[Dict[str, List[str]], str]:
    """Each rule's expansion as tokens, and the name of the first public rule."""
    body = _COMMENT.sub(" ", jsgf)
    body = "\n".join(line for line in body.splitlines() if not line.lstrip().startswith("#"))
    rules: Dict[str, List[str]] = {}
    public: Optional[str] = None
    for statement in body.split(";"):
        words = statement.split(None, 1)
        if not words or words[0] in ("grammar", "import"):
            continue
        is_public = words[0] == "public"
        definition = words[1] if is_public and len(words) > 1 else statement
        name, equals, expansion = definition.partition("=")
        name = name.strip()
        if not equals or not re.match(r"^<[^<>\s]+>$", name):
            raise GrammarError(f"{source}: cannot read {statement.strip()!r}; a rule is <name> = expansion;")
        rules[name[1:-1]] = _TOKEN.findall(expansion)
        if is_public and public is None:
            public = name[1:-1]
    if public is None:
        raise GrammarError(f"{source}: no public rule; pocketsphinx takes the first 'public <name> = ...;'")
    return rules, public


def _expand(tokens: List[str], rules: Dict[str, List[str]], source: str, seen: Tuple[str, ...]) -> Sentences:
    """The sentences of an expansion: alternatives of sequences of items."""
    alternatives: List[List[str]] = [[]]
    depth = 0
    for token in tokens:
        depth += token in "(["
        depth -= token in ")]"
        if token == "|" and depth == 0:
            alternatives.append([])
        else:
            alternatives[-1].append(token)
    result: Set[Tuple[str, ...]] = set()
    for alternative in alternatives:
        result |= _sequence(alternative, rules, source, seen)
        if len(result) > MAX_SENTENCES:
            raise _TooMany
    return frozenset(result)


def _sequence(
    tokens: List[str], rules: Dict[str, List[str]], source: str, seen: Tuple[str, ...]
) -> Sentences:
    sentences: Set[Tuple[str, ...]] = {()}
    index = 0
    while index < len(tokens):
        token = tokens[index]
        index += 1
        if token.startswith(("/", "{")):
            continue  # weights and tags do not change which sentences are allowed
        if token in "([":
            end = _closing(tokens, index - 1, source)
            inner = _expand(tokens[index:end], rules, source, seen)
            item = inner | {()} if token == "[" else inner
            index = end + 1
        elif token.startswith("<"):
            name = token[1:-1]
            if name in ("NULL",):
                item = frozenset({()})
            elif name == "VOID" or name in seen:
                raise _TooMany  # <VOID> or recursion: not a finite list we can score
            elif name not in rules:
                raise GrammarError(f"{source}: rule <{name}> is used but not defined")
            else:
                item = _expand(rules[name], rules, source, (*seen, name))
        elif token in ("*", "+"):
            raise _TooMany
        elif not _is_word(token):
            raise GrammarError(f"{source}: unexpected {token!r} in the grammar")
        else:
            word = token.lower()
            if not _WORD.match(word):
                raise GrammarError(f"{source}: {token!r} is not a word of a-z and '")
            item = frozenset({(word,)})
        if index < len(tokens) and tokens[index] in ("*", "+"):
            raise _TooMany
        sentences = {left + right for left, right in itertools.product(sentences, item)}
        if len(sentences) > MAX_SENTENCES:
            raise _TooMany
    return frozenset(sentences)


def _is_word(token: str) -> bool:
    """Whether a JSGF token is a word, not a rule, weight, tag, bracket or operator."""
    return not token.startswith(("<", "/", "{")) and token not in (
        "(",
        ")",
        "[",
        "]",
        "|",
        "*",
        "+",
        "=",
        ";",
    )


def _closing(tokens: List[str], opening: int, source: str) -> int:
    """The index of the bracket that closes the one at ``opening``."""
    depth = 0
    for index in range(opening, len(tokens)):
        depth += tokens[index] in "(["
        depth -= tokens[index] in ")]"
        if depth == 0:
            return index
    raise GrammarError(f"{source}: {tokens[opening]!r} is never closed")
