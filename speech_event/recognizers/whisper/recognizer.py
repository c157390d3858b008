"""The Whisper family on onnxruntime: Whisper's log-mel -> encoder -> greedy decoding with
Whisper's rules (decoder with a key/value cache) -> tokens -> text.

Audio longer than 30 s (Whisper's window) is cut at its quietest 0.1 s between 20 and 30 s into
each piece; the pieces' texts are joined. A piece where nothing was said gives no text, by
whisper.transcribe's own tests: its no-speech probability above ``no_speech_threshold`` (0.6), or
its text a decoding loop, compressing by more than ``compression_ratio_threshold`` (2.4). Unlike
whisper's, the no-speech test holds whatever the text's log-probability: tiny.en writes "you" for
brown noise at -0.7 a token. Measured on tiny.en int8 (docs/benchmarks.md): 0.79 to 0.96 on
white, pink and brown noise; on people's words it heard right 0.37 at most, 0.43 under pink
noise at 10 dB, and above 0.6 only where it misheard. Babble is not told apart this way (0.41 to
0.80: six people talking are speech). Confidence: 1 - no_speech_prob of the first piece, as the
robot's node reports it. A language with no token in the model directory's config.json (Whisper
has none for Kinyarwanda) is refused when the engine is built.

With a grammar in force: the free greedy decoding, then each phrase that can decide scored by
teacher forcing (forced.py) along the forms' prefix tree (phrase_tree.py: the others bounded by
the prefix that rules them out) in the forms Whisper writes
it (written_forms.py: its usual ones, and for a phrase the free text may be a mishearing of, the
phrase in the free text's punctuation), each form in the tokens Whisper's tokenizer gives it
(tokenizer.py); the phrase the free text's words take (the free text, or the phrase it is a
mishearing of), else the phrases evidence_candidates names, scored against silence too
(forced.UnheardScores: the audio's evidence for them); the answer chosen as
onnx/grammar_choice.py says. A command fits in Whisper's 30 s window: only the first
piece is decoded then.
"""

import dataclasses
import zlib
from pathlib import Path
from typing import Dict, List, Optional, Tuple, Union

import numpy as np
import onnxruntime

from speech_event.errors import GrammarError, ModelError
from speech_event.grammar import Grammar
from speech_event.ports import Transcript
from speech_event.recognizers.onnx.compiled_grammars import CompiledGrammars
from speech_event.recognizers.onnx.directory import CPU_FP32, Runtime, exported_directory
from speech_event.recognizers.onnx.grammar_choice import (
    NEURAL_GRAMMAR_THRESHOLD,
    GrammarChoice,
    heard_as,
    least_deciding_score,
)
from speech_event.recognizers.onnx.session import StoppableRuns
from speech_event.recognizers.whisper.features import CHUNK_SAMPLES, SAMPLE_RATE, whisper_log_mel
from speech_event.recognizers.whisper.forced import UnheardScores
from speech_event.recognizers.whisper.greedy import WhisperResult, whisper_greedy
from speech_event.recognizers.whisper.layouts import load_whisper_directory
from speech_event.recognizers.whisper.manifest import MANIFEST_FILE, text_of
from speech_event.recognizers.whisper.phrase_tree import score_phrases_that_decide
from speech_event.recognizers.whisper.tokenizer import WhisperTokenizer
from speech_event.recognizers.whisper.written_forms import phrase_as_written, phrase_variants
from speech_event.spelling import spelt

NO_SPEECH_THRESHOLD = 0.6  # whisper.transcribe's defaults
COMPRESSION_RATIO_THRESHOLD = 2.4
SHORTEST_PIECE = 20 * SAMPLE_RATE
QUIET_WINDOW = SAMPLE_RATE // 10
ENGINE = "the Whisper engine"
# A grammar's phrases, each with the token sequences of the forms the model can spell.
PhraseForms = Dict[str, List[List[int]]]


def compression_ratio(text: str) -> float:
    """How much zlib compresses ``text`` (whisper.utils.compression_ratio): a loop compresses well."""
    written = text.encode("utf-8")
    return len(written) / len(zlib.compress(written)) if written else 0.0


def pieces_at_quiet_points(audio: np.ndarray) -> List[np.ndarray]:
    """``audio`` in pieces of at most 30 s, each cut at the quietest 0.1 s window from 20 s on."""
    pieces: List[np.ndarray] = []
    while audio.size > CHUNK_SAMPLES:
        search = audio[SHORTEST_PIECE:CHUNK_SAMPLES]
        windows = search[: search.size // QUIET_WINDOW * QUIET_WINDOW].reshape(-1, QUIET_WINDOW)
        quietest = int(np.argmin(np.square(windows.astype(np.float64)).sum(axis=1)))
        cut = SHORTEST_PIECE + quietest * QUIET_WINDOW + QUIET_WINDOW // 2
        pieces.append(audio[:cut])
        audio = audio[cut:]
    pieces.append(audio)
    return pieces


class WhisperRecognizer:
    """The Recognizer port on an exported Whisper model directory, for one language; Stoppable."""

    def __init__(
        self,
        model_directory: Union[str, Path],
        language: str,
        runtime: Runtime = CPU_FP32,
        grammar: Optional[Grammar] = None,
        grammar_threshold: Optional[float] = None,
        no_speech_threshold: Optional[float] = NO_SPEECH_THRESHOLD,
        compression_ratio_threshold: Optional[float] = COMPRESSION_RATIO_THRESHOLD,
    ) -> None:
        """``grammar_threshold``: see onnx/grammar_choice.py (the ``grammar_threshold`` key); None:
        NEURAL_GRAMMAR_THRESHOLD. ``no_speech_threshold``, ``compression_ratio_threshold``: a piece
        of free speech above either says nothing (None: no such test), as whisper.transcribe's
        options of those names."""
        directory = exported_directory(model_directory, ".pt", "export-whisper")
        self._manifest, self._pieces, self._model = load_whisper_directory(directory, runtime)
        if language not in self._manifest.languages:
            named = ", ".join(sorted(self._manifest.languages)) or "none"
            raise ModelError(
                f"the Whisper model in {directory} has no language token for {language} (Whisper has "
                f"none for Kinyarwanda; this model's languages: {named}); export a checkpoint fine-tuned "
                f"with one, naming it: speech-event export-whisper CHECKPOINT DIR --language {language}=CODE"
            )
        self._prompt = self._manifest.prompt(language)
        self._tokenizer = WhisperTokenizer(self._pieces, self._manifest.eot)
        self._unheard = UnheardScores(self._model, self._prompt, self._manifest)
        if len(self._pieces) != self._manifest.vocabulary_size or self._model.vocabulary_size not in (
            None,
            self._manifest.vocabulary_size,
        ):
            raise ModelError(
                f"{directory}: the tokenizer's files hold {len(self._pieces)} tokens, {MANIFEST_FILE} says "
                f"{self._manifest.vocabulary_size}, the decoder gives {self._model.vocabulary_size} logits: "
                "the files are not of one export"
            )
        self._runs = StoppableRuns()
        self._no_speech_threshold = no_speech_threshold
        self._compression_ratio_threshold = compression_ratio_threshold
        self._threshold = NEURAL_GRAMMAR_THRESHOLD if grammar_threshold is None else grammar_threshold
        self._grammars = CompiledGrammars(self._forms)
        self._grammars.use(grammar)
        self._last_choice: Optional[GrammarChoice] = None

    @property
    def sample_rate(self) -> int:
        return SAMPLE_RATE

    def check_grammar(self, grammar: Grammar) -> None:
        """Every phrase must be spelt by the model's tokens in at least one form. A grammar checked is
        about to be used (set_grammar, the grammar key): the silence its phrases' evidence is
        scored against is encoded now, not in the recognition of the first command said."""
        self._grammars.compiled(grammar)
        self._unheard.prepare()

    def use_grammar(self, grammar: Optional[Grammar]) -> None:
        self._grammars.use(grammar)

    def _forms(self, grammar: Grammar) -> PhraseForms:
        """Each phrase's token sequences, one for each form the model can spell."""
        compiled = {}
        for phrase in grammar.sentences(ENGINE):
            forms = []
            for variant in phrase_variants(phrase):
                try:
                    forms.append(self._tokenizer.encode(variant))
                except ModelError:
                    continue  # a form the model cannot spell (a tokenizer without capitals)
            if not forms:
                raise GrammarError(f"{grammar.source}: {ENGINE}'s tokens cannot spell {phrase!r}")
            compiled[phrase] = forms
        return compiled

    def decode(self, audio: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> WhisperResult:
        """Whisper's greedy decoding of one piece of at most 30 s."""
        decoding = self._model.decoding(whisper_log_mel(audio, self._manifest.mel_bands), run)
        return whisper_greedy(decoding, self._prompt, self._manifest)

    @property
    def last_choice(self) -> Optional[GrammarChoice]:
        """The grammar decision of the last transcribe within a grammar (its free text and every
        phrase's score: the ratio each was judged by); None after free speech."""
        return self._last_choice

    def transcribe(self, audio: np.ndarray) -> Transcript:
        run = self._runs.start()
        grammar = self._grammars.in_force
        self._last_choice = None
        if grammar is not None:
            return self._within(
                self._grammars.compiled(grammar),
                pieces_at_quiet_points(np.asarray(audio, np.float32))[0],
                run,
            )
        results = [self.decode(piece, run) for piece in pieces_at_quiet_points(np.asarray(audio, np.float32))]
        texts = [self._said(result) for result in results]
        no_speech = results[0].no_speech_prob
        return Transcript(
            " ".join(text for text in texts if text), None if no_speech is None else 1.0 - no_speech
        )

    def _said(self, result: WhisperResult) -> str:
        """The text of one piece of free speech, or "" where nothing was said."""
        text = text_of(result.tokens, self._pieces, self._manifest.timestamp_begin).strip()
        no_speech, most = result.no_speech_prob, self._no_speech_threshold
        if no_speech is not None and most is not None and no_speech > most:
            return ""
        loop = self._compression_ratio_threshold
        return "" if loop is not None and compression_ratio(text) > loop else text

    def _within(self, forms: PhraseForms, audio: np.ndarray, run: onnxruntime.RunOptions) -> Transcript:
        """The phrase of the grammar said in ``audio`` (at most 30 s), or none."""
        decoding = self._model.decoding(whisper_log_mel(audio, self._manifest.mel_bands), run)
        prompted = decoding(self._prompt)  # one pass, from which the free text and the phrases go on
        free = whisper_greedy(decoding.fork(), self._prompt, self._manifest, prompted)
        free_text = text_of(free.tokens, self._pieces, self._manifest.timestamp_begin)
        owners: List[Tuple[str, List[int]]] = [
            (phrase, tokens) for phrase, each in forms.items() for tokens in each
        ]
        owners += self._as_written(forms, free_text)
        sequences = [tokens for _, tokens in owners]
        said = spelt(free_text)  # its phrase's evidence needs its exact score
        scores = score_phrases_that_decide(
            decoding,
            self._prompt,
            sequences,
            self._manifest,
            prompted,
            least_deciding_score(free.score, self._threshold),
            [index for index, (phrase, _) in enumerate(owners) if phrase == said],
        )
        best: Dict[str, Tuple[float, List[int]]] = {}
        for (phrase, tokens), score in zip(owners, scores):
            if phrase not in best or score > best[phrase][0]:
                best[phrase] = score, tokens
        choice = GrammarChoice(free_text, free.score, {phrase: score for phrase, (score, _) in best.items()})
        confidence = None if free.no_speech_prob is None else 1.0 - free.no_speech_prob
        # A phrase the words take is taken only on the audio's evidence for it; where they take
        # none, the evidence may take a candidate.
        taken = choice.taken_by_the_words(self._threshold)
        unheard = [taken] if taken is not None else choice.evidence_candidates(self._threshold)
        choice = self._with_evidence(choice, best, unheard, run)
        self._last_choice = choice
        return choice.transcript(self._threshold, confidence)

    def _with_evidence(
        self,
        choice: GrammarChoice,
        best: Dict[str, Tuple[float, List[int]]],
        phrases: List[str],
        run: onnxruntime.RunOptions,
    ) -> GrammarChoice:
        """``choice`` with the audio's evidence for ``phrases``: each one's best form scored with
        the audio, less the same tokens scored against silence."""
        unheard = self._unheard([best[phrase][1] for phrase in phrases])
        if run.terminate:  # stopped during the calls on silence, which are not stoppable
            raise RuntimeError(f"{ENGINE}: transcription stopped (RunOptions.terminate)")
        evidence = {phrase: best[phrase][0] - prior for phrase, prior in zip(phrases, unheard)}
        return dataclasses.replace(choice, evidence={**choice.evidence, **evidence})

    def _as_written(self, forms: PhraseForms, free_text: str) -> List[Tuple[str, List[int]]]:
        """Each phrase the free text is that phrase misheard (the only phrases the decision may
        take besides the free text itself), written as the free text is, where that is a form the
        phrase has not: scored too, so that the phrase is judged in Whisper's own punctuation."""
        said = spelt(free_text)
        if said in forms:
            return []  # the free text is a phrase: the decision takes it
        written = []
        for phrase, each in forms.items():
            if not heard_as(said, phrase):
                continue
            try:
                tokens = self._tokenizer.encode(phrase_as_written(phrase, free_text))
            except ModelError:
                continue  # written with a letter the model cannot write; its other forms stand
            if tokens not in each:
                written.append((phrase, tokens))
        return written

    def stop(self) -> None:
        """Stop the transcribe running now: its next onnxruntime call raises."""
        self._runs.stop()

    def closes_sentences(self) -> bool:
        return True
