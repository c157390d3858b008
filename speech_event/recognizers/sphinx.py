"""The embedded English recognizer: pocketsphinx, whose English model ships inside its wheel.

Three modes, by configuration: its language model (any English; the default); a grammar for a
robot's command vocabulary (``pocketsphinx_grammar``: a JSGF file, or a plain text file of phrases,
one per line, compiled to a JSGF grammar); a keyword list (``pocketsphinx_keywords``: one phrase a
line, optionally with its threshold as ``/1e-20/``, pocketsphinx's kws format).
"""

import re
from pathlib import Path
from typing import Dict, List, Optional, Set

import numpy as np

from speech_event.errors import ModelError
from speech_event.ports import Transcript

SAMPLE_RATE = 16000
_WORD = re.compile(r"^[a-z']+$")
_PHRASE = re.compile(r"\( ([a-z' ]+) \)")
# Keyword spotting fires several times on one spoken keyword: detections of the same keyword that
# start within this many frames (10 ms each) of the previous one's end are one.
_SAME_KEYWORD_FRAMES = 50


def phrases_to_jsgf(phrases: List[str], source: str = "<phrases>") -> str:
    """A JSGF grammar whose sentences are exactly ``phrases`` (lowercase words)."""
    cleaned = [" ".join(phrase.lower().split()) for phrase in phrases]
    cleaned = [phrase for phrase in cleaned if phrase and not phrase.startswith("#")]
    if not cleaned:
        raise ModelError(f"{source}: no phrases; write one command phrase a line")
    for phrase in cleaned:
        bad = [word for word in phrase.split() if not _WORD.match(word)]
        if bad:
            raise ModelError(f"{source}: {phrase!r} has {bad[0]!r}; phrases are words of a-z and '")
    alternatives = " | ".join(f"( {phrase} )" for phrase in dict.fromkeys(cleaned))
    return f"#JSGF V1.0;\ngrammar commands;\npublic <command> = {alternatives};\n"


class SphinxRecognizer:
    """The Recognizer port on pocketsphinx: its English language model, a grammar, or a keyword list."""

    def __init__(self, grammar: str = "", keywords: str = "") -> None:
        from pocketsphinx import Decoder  # only when this engine is chosen

        if grammar and keywords:
            raise ModelError("set pocketsphinx_grammar or pocketsphinx_keywords, not both")
        self._decoder = Decoder(samprate=SAMPLE_RATE, loglevel="FATAL")
        self._spotting = bool(keywords)
        # The sentences of a phrase-list grammar: pocketsphinx returns its best partial path when
        # no sentence fits (measured: "tell" for a "stop" it missed), which must not be published.
        self._phrases: Optional[Set[str]] = None
        self._grammar = bool(grammar)
        if grammar:
            self._use_grammar(Path(grammar))
        elif keywords:
            path = Path(keywords)
            if not path.is_file():
                raise ModelError(f"{path}: no such keyword list (pocketsphinx_keywords)")
            self._decoder.add_kws("keywords", str(path))
            self._decoder.activate_search("keywords")

    def _use_grammar(self, path: Path) -> None:
        try:
            content = path.read_text(encoding="utf-8")
        except OSError as problem:
            raise ModelError(
                f"{path}: cannot read the grammar (pocketsphinx_grammar): {problem.strerror}"
            ) from None
        if content.lstrip().startswith("#JSGF"):
            jsgf = content
        else:
            jsgf = phrases_to_jsgf(content.splitlines(), str(path))
            self._phrases = set(_PHRASE.findall(jsgf))
        words = set(re.findall(r"[a-z']+", _sentences(jsgf)))
        unknown = sorted(word for word in words if self._decoder.lookup_word(word) is None)
        if unknown:
            raise ModelError(f"{path}: words not in pocketsphinx's English dictionary: {', '.join(unknown)}")
        self._decoder.add_jsgf_string("grammar", jsgf)
        self._decoder.activate_search("grammar")

    @property
    def sample_rate(self) -> int:
        return SAMPLE_RATE

    @property
    def whole_phrases(self) -> bool:
        """In grammar mode every text is a whole phrase of the grammar (early end of turn)."""
        return self._grammar

    def transcribe(self, audio: np.ndarray) -> Transcript:
        pcm = np.clip(np.round(audio * 32767.0), -32768, 32767).astype("<i2").tobytes()
        self._decoder.start_utt()
        self._decoder.process_raw(pcm, full_utt=True)
        self._decoder.end_utt()
        if self._spotting:
            return Transcript(" ".join(self._keywords_in_order()))
        hypothesis = self._decoder.hyp()
        text = "" if hypothesis is None else " ".join(hypothesis.hypstr.split())
        if self._phrases is not None and text not in self._phrases:
            text = ""
        # No confidence: pocketsphinx computes no posterior unless asked to (its prob stays 0).
        return Transcript(text)

    def _keywords_in_order(self) -> List[str]:
        words: List[str] = []
        last_end: Dict[str, int] = {}
        for segment in sorted(self._decoder.seg() or [], key=lambda segment: segment.start_frame):
            word = segment.word.strip()
            repeated = word in last_end and segment.start_frame - last_end[word] < _SAME_KEYWORD_FRAMES
            last_end[word] = segment.end_frame
            if not repeated:
                words.append(word)
        return words


def _sentences(jsgf: str) -> str:
    """The right-hand sides of a JSGF grammar, where its words are."""
    return " ".join(line.split("=", 1)[1] for line in jsgf.splitlines() if "=" in line)
