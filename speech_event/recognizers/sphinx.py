"""The embedded English recognizer: pocketsphinx, whose English model ships inside its wheel.

Three modes: its language model (any English; the default); a command grammar (a ``Grammar``,
speech_event/grammar.py: pocketsphinx searches its JSGF itself, so a grammar of any size works); a
keyword list (``pocketsphinx_keywords``: one phrase a line, optionally with its threshold as
``/1e-20/``, pocketsphinx's kws format).

Within a grammar pocketsphinx always answers with the nearest phrase ("please open the window"
came out as "open the door"), so speech outside the grammar is rejected by a likelihood ratio
(issue 19). One decoder decodes the utterance twice: within the grammar, and freely with its
English language model, weighted 3 instead of 6.5 so that the free decoding follows the sound
more than the language model. The ratio, in nats, for the whole utterance:

    ratio = ln P(audio, best phrase | grammar) - ln P(audio, best words | language model)

each the score pocketsphinx gives its best path (Hypothesis.score): the acoustic log-likelihood
plus the weighted grammar or language-model log-probabilities and insertion penalties, in nats
(_SCORE_SCALE). The phrase is published when ratio >= threshold; otherwise the text is empty and
``rejected`` names the phrase. The grammars are searched with beams wider than pocketsphinx's
(_GRAMMAR_SETTINGS), so that the phrase is the grammar's most likely, not one a pruned search
happened to keep. Not per second, like the neural engines' ratio: a wrong word costs
about the same in a long command as in a short one; and on the sets of bench/figures/grammar.py the worst
command against the best near miss, tts voice, -62 against -121 nats in total, -75 against -106
nats per second.

What makes the two scores comparable (measured, pocketsphinx 5.1): ``compallsen``, every senone
scored every frame, so both searches normalise a frame by the same best senone (without it the
ratios of commands and of other speech overlap entirely); and ``bestpath`` off (its lattice pass
leaves the last word's acoustic score out of the hypothesis' score, so a final silence swallowed
trailing words for nothing: "go to the kitchen later" scored better as "go to the kitchen" than
the command said alone). Without ``bestpath`` a grammar has no hypothesis when no path reaches the
grammar's end: only whole sentences are published, and the best partial path is only named as
``rejected``. Also measured, and worse: a phone loop (allphone, with or without its phone language
model) as the free decoding: commands and near misses overlap (-161 against -159 nats a second at
best).
"""

import math
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Dict, Iterator, List, Mapping, Optional, Union

import numpy as np

from speech_event.errors import GrammarError, ModelError
from speech_event.grammar import Grammar
from speech_event.ports import Transcript

SAMPLE_RATE = 16000
# nats (the ratio above). bench/figures/grammar.py through the node, pocketsphinx 5.1.1 and its en-us model,
# each utterance decoded afresh (_start_afresh), the robot's 32 commands and 65 other sentences in
# four voices (issue 32): commands -59 to +57 in espeak's voice, down to -113 in festival's kal and
# -143 in ked; other speech at most -115 (espeak), -107 (kal: "bring me the red book"), -168 (ked),
# and slt's "bring me the red book" at -61, within any threshold that takes its commands. -100
# takes every command down to it (-90 left out kal's "come here" at -95 and three more) and no
# other sentence that -90 did not; the cards recordings score -72 to -46 against cards.gram, the
# librivox ones -4772 to -1142. A false command is worse than none: measure before going lower.
DEFAULT_GRAMMAR_THRESHOLD = -100.0
# Keyword spotting fires several times on one spoken keyword: detections of the same keyword that
# start within this many frames (10 ms each) of the previous one's end are one.
_SAME_KEYWORD_FRAMES = 50
# pocketsphinx scores paths in units of 2**10 of its log base (SENSCR_SHIFT); its Python binding
# hands a score out as LOGBASE**score, so ln(Hypothesis.score) * 2**10 is the path's score in nats.
_SCORE_SCALE = 2.0**10
_FREE = "_free"
_Setting = Union[bool, int, float]
# The free decoding: language weight 3 (measured: 4 and 5 separate less, 1 takes 1.5 s a second of
# audio; in festival's voices too, no weight from 2 to 8 parts every command from other speech); no
# second (fwdflat) pass and at most 1500 HMMs a frame: the same ratios, 3 times faster. The
# grammars' searches keep pocketsphinx's other defaults (read live: maxhmmpf), so these are restored.
_FREE_SETTINGS: Mapping[str, _Setting] = {
    "lw": 3.0,
    "fwdflatlw": 3.0,
    "bestpathlw": 3.0,
    "fwdflat": False,
    "maxhmmpf": 1500,
}
# The grammars' searches: beams wider than pocketsphinx's defaults (beam and pbeam 1e-48, wbeam
# 7e-29), read when a search is made. With the defaults festival's slt voice saying "come here"
# came out as "thank you", 381 nats less likely than "come here" in the same grammar: the right
# path had been pruned within its first word. A grammar's search is small (the robot's 32
# commands), and even pocketsphinx's cards grammar of 1.4 million sentences costs 0.086 s a second
# of audio with these against 0.076.
_GRAMMAR_SETTINGS: Mapping[str, _Setting] = {"beam": 1e-80, "wbeam": 1e-60, "pbeam": 1e-80}


class SphinxRecognizer:
    """The Recognizer port on pocketsphinx: its English language model, a command grammar (speech
    outside it rejected), or a keyword list. Implements ``Grammars`` and ``Incremental``."""

    def __init__(
        self,
        grammar: Optional[Grammar] = None,
        keywords: str = "",
        grammar_threshold: Optional[float] = None,
    ) -> None:
        """``grammar_threshold``: the least ratio (module docstring) for a phrase to be published;
        None: DEFAULT_GRAMMAR_THRESHOLD; -inf: no rejection (and no free decoding)."""
        if grammar is not None and keywords:
            raise ModelError("set grammar or pocketsphinx_keywords, not both")
        if keywords and not Path(keywords).is_file():
            raise ModelError(f"{keywords}: no such keyword list (pocketsphinx_keywords)")
        self._keywords = keywords
        self._threshold = DEFAULT_GRAMMAR_THRESHOLD if grammar_threshold is None else grammar_threshold
        # Two decoders, each made when first needed: free speech (and keywords) as pocketsphinx
        # decodes by default, and grammars, whose searches and their free decoding share one
        # decoder made with compallsen. compallsen is a decoder's, not a search's, and costs the
        # language model a quarter more time (LibriVox: 0.115 -> 0.145 s a second of audio).
        self._plain: Any = None
        self._grammar_decoder: Any = None
        self._searches: Dict[str, str] = {}  # JSGF text -> its search, compiled once
        self._search: Optional[str] = None  # the grammar's search in force; None: language model
        self._last_ratio: Optional[float] = None
        # Partial results (Incremental) decode on a third decoder, made at the first partial, so
        # they never change what the others decode; its searches are named by their JSGF text.
        self._partial: Any = None
        self._partial_searches: Dict[str, str] = {}
        self._partial_open = False  # an utterance is being fed to it
        if keywords:
            self._plain_decoder().add_kws("keywords", keywords)
            self._plain_decoder().activate_search("keywords")
        self.use_grammar(grammar)

    @property
    def sample_rate(self) -> int:
        """pocketsphinx's model is of 16 kHz speech."""
        return SAMPLE_RATE

    @property
    def last_ratio(self) -> Optional[float]:
        """The ratio (module docstring) the last transcribe within a grammar judged by; None when
        it reached no phrase or did not judge (language model, keywords, no rejection)."""
        return self._last_ratio

    def check_grammar(self, grammar: Grammar) -> None:
        """GrammarError when this engine cannot decode within ``grammar``: a keyword list is in
        force, the JSGF does not parse, or words are not in pocketsphinx's dictionary (named)."""
        if self._keywords:
            raise GrammarError(
                f"{grammar.source}: a keyword list (pocketsphinx_keywords) is in force; pocketsphinx "
                "decodes with a grammar or a keyword list, not both"
            )
        if grammar.jsgf in self._searches:
            return
        decoder = self._grammars()
        unknown = [word for word in grammar.words() if decoder.lookup_word(word) is None]
        if unknown:
            raise GrammarError(
                f"{grammar.source}: words not in pocketsphinx's English dictionary: {', '.join(unknown)}"
            )
        try:
            decoder.parse_jsgf(grammar.jsgf)
        except ValueError:
            raise GrammarError(f"{grammar.source}: pocketsphinx cannot read the JSGF grammar") from None

    def use_grammar(self, grammar: Optional[Grammar]) -> None:
        """Decode within ``grammar`` from the next transcribe on (None: the language model). Each
        distinct grammar is compiled once, so switching back and forth costs nothing."""
        if grammar is None:
            self._search = None
            return
        self.check_grammar(grammar)  # at once when it is compiled already
        decoder = self._grammars()
        with _settings(decoder, _GRAMMAR_SETTINGS):
            self._search = _compiled_search(decoder, self._searches, grammar.jsgf)

    def transcribe(self, audio: np.ndarray) -> Transcript:
        """The text of one utterance; with a grammar, a whole phrase of it or none (``rejected``)."""
        pcm = _pcm(audio)
        self._last_ratio = None
        if self._search is not None:
            return self._within_grammar(self._search, pcm)
        decoder = self._plain_decoder()
        _decode(decoder, pcm)
        if self._keywords:
            return Transcript(" ".join(self._keywords_in_order()))
        hypothesis = decoder.hyp()
        # No confidence: pocketsphinx computes no posterior unless asked to (its prob stays 0).
        return Transcript("" if hypothesis is None else " ".join(hypothesis.hypstr.split()))

    def begin_partial(self, grammar: Optional[Grammar]) -> None:
        """A new utterance on the partial decoder, in the mode of final texts: the keyword list,
        ``grammar``, or the language model."""
        decoder = self._partial_decoder()
        if self._partial_open:
            decoder.end_utt()
        if grammar is not None and not self._keywords:
            decoder.activate_search(_compiled_search(decoder, self._partial_searches, grammar.jsgf))
        else:
            decoder.activate_search(self._partial_searches[""])
        _start_afresh(decoder)
        self._partial_open = True

    def feed_partial(self, audio: np.ndarray) -> Transcript:
        """The best path so far after ``audio`` (for a grammar: the phrase so far, which need not
        be whole; for keywords: the keywords heard so far)."""
        if not self._partial_open:  # pocketsphinx would answer nothing, and say nothing of why
            raise RuntimeError("feed_partial before begin_partial: no utterance on the partial decoder")
        decoder = self._partial_decoder()
        if audio.size:  # a resampler's first piece may be empty; pocketsphinx raises on no samples
            decoder.process_raw(_pcm(audio), no_search=False, full_utt=False)
        hypothesis = decoder.hyp()
        return Transcript("" if hypothesis is None else " ".join(hypothesis.hypstr.split()))

    def _partial_decoder(self) -> Any:
        """The decoder of partial results: the forward search only (no second pass, no lattice),
        which is what a text so far needs; its free search named by the empty JSGF text."""
        if self._partial is None:
            from pocketsphinx import Decoder

            decoder = Decoder(samprate=SAMPLE_RATE, loglevel="FATAL", fwdflat=False, bestpath=False)
            if self._keywords:
                decoder.add_kws("keywords", self._keywords)
                decoder.activate_search("keywords")
            self._partial_searches[""] = decoder.current_search()
            self._partial = decoder
        return self._partial

    def _within_grammar(self, search: str, pcm: bytes) -> Transcript:
        decoder = self._grammars()
        decoder.activate_search(search)
        partial = _decode(decoder, pcm, partial=True)
        best = decoder.hyp()
        phrase = "" if best is None else " ".join(best.hypstr.split())
        if not phrase:
            # No path reached the grammar's end: the best partial path ("go to the living") is
            # what the speech was nearest to, never published.
            return Transcript("", rejected=partial or None)
        if self._threshold == -math.inf:
            return Transcript(phrase)
        grammar_score = _nats(best.score)
        decoder.activate_search(_FREE)
        _decode(decoder, pcm)
        free = decoder.hyp()
        # No free hypothesis (nothing the language model could say): the grammar's path stands alone.
        ratio = 0.0 if free is None else grammar_score - _nats(free.score)
        self._last_ratio = ratio
        return Transcript(phrase) if ratio >= self._threshold else Transcript("", rejected=phrase)

    def _plain_decoder(self) -> Any:
        """pocketsphinx as it decodes by default: its language model (and any keyword list)."""
        if self._plain is None:
            from pocketsphinx import Decoder  # only when this engine is chosen

            self._plain = Decoder(samprate=SAMPLE_RATE, loglevel="FATAL")
        return self._plain

    def _grammars(self) -> Any:
        """The decoder of the grammars' searches and of their free decoding (_FREE_SETTINGS)."""
        if self._grammar_decoder is None:
            from pocketsphinx import Decoder, NGramModel

            decoder = Decoder(
                samprate=SAMPLE_RATE, loglevel="FATAL", compallsen=True, bestpath=False, lm=None
            )
            with _settings(decoder, _FREE_SETTINGS):
                # pocketsphinx applies the language weight when it reads a model
                model = NGramModel(decoder.config, decoder.logmath, _language_model())
                decoder.add_lm(_FREE, model)
            self._grammar_decoder = decoder
        return self._grammar_decoder

    def _keywords_in_order(self) -> List[str]:
        words: List[str] = []
        last_end: Dict[str, int] = {}
        for segment in sorted(self._plain_decoder().seg() or [], key=lambda segment: segment.start_frame):
            word = segment.word.strip()
            repeated = word in last_end and segment.start_frame - last_end[word] < _SAME_KEYWORD_FRAMES
            last_end[word] = segment.end_frame
            if not repeated:
                words.append(word)
        return words


def _compiled_search(decoder: Any, searches: Dict[str, str], jsgf: str) -> str:
    """The name of ``decoder``'s search for the grammar ``jsgf``, added to it the first time
    (``searches``: that decoder's, JSGF text -> name): each grammar is compiled once."""
    search = searches.get(jsgf)
    if search is None:
        search = f"grammar{len(searches)}"
        decoder.add_jsgf_string(search, jsgf)
        searches[jsgf] = search
    return search


def _pcm(audio: np.ndarray) -> bytes:
    """Float samples in [-1, 1] as the 16-bit little-endian PCM pocketsphinx reads."""
    return np.clip(np.round(audio * 32767.0), -32768, 32767).astype("<i2").tobytes()


def _decode(decoder: Any, pcm: bytes, partial: bool = False) -> str:
    """Decode one utterance with the decoder's active search; with ``partial``, the best path
    before the utterance ends (for a grammar: which need not reach the grammar's end)."""
    _start_afresh(decoder)
    decoder.process_raw(pcm, full_utt=True)
    before_end = decoder.hyp() if partial else None
    decoder.end_utt()
    return "" if before_end is None else " ".join(before_end.hypstr.split())


def _start_afresh(decoder: Any) -> None:
    """Start an utterance as a new decoder would. A decoder's feature extraction keeps what it
    learned of the utterances before (the noise estimate and the cepstral mean among others): the
    same cards recording scored up to 20 nats apart by what the decoder had heard before it, enough
    to cross the grammar's threshold. Made anew from the configuration (0.1 ms), each utterance is
    decoded exactly as by a fresh decoder, in any order (tests/recognizers/test_sphinx_isolation.py)."""
    decoder.reinit_feat()
    decoder.start_utt()


@contextmanager
def _settings(decoder: Any, settings: Mapping[str, _Setting]) -> Iterator[None]:
    """pocketsphinx reads these when a search is made: made with them, then restored."""
    config = decoder.config
    saved = {key: config[key] for key in settings}
    try:
        for key, value in settings.items():
            config[key] = value
        yield
    finally:
        for key, value in saved.items():
            config[key] = value


def _language_model() -> str:
    import pocketsphinx

    return str(Path(pocketsphinx.get_model_path()) / "en-us" / "en-us.lm.bin")


def _nats(score: float) -> float:
    """A path score as its binding hands it out, in nats (-inf when it underflowed)."""
    return math.log(score) * _SCORE_SCALE if score > 0.0 else -math.inf
