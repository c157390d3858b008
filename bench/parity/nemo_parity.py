"""Parity of the engine with NeMo itself (a tool, not CI): needs torch and nemo_toolkit.

    python3 -m venv /tmp/nemo && /tmp/nemo/bin/pip install torch==2.13.0 "nemo_toolkit[asr]"
    PYTHONPATH=. /tmp/nemo/bin/python -m bench.parity.nemo_parity [NAME ...]  # default: every model below

Builds randomly initialised NeMo models of realistic size with a small SentencePiece tokenizer
(random_nemo.py), saves each as .nemo, exports it with ``speech-event export-nemo`` (NeMo's own
exporter underneath) and checks that the engine gives NeMo's own transcription (``model.transcribe``,
its default greedy_batch decoding) of the same model on the 10 parity sentences (sentences.py): the
same tokens, and the confidence (exp of NeMo's hypothesis score). The models:

- conformer-rnnt: the conformer-transducer large (17 blocks, d_model 512, 4x striding);
- fastconformer-hybrid: a FastConformer hybrid RNN-T/CTC (EncDecHybridRNNTCTCBPEModel, as the
  robot loads Parakeet; 17 blocks, d_model 512, 8x depthwise striding), both heads exported;
- fastconformer-tdt: a FastConformer TDT (EncDecRNNTBPEModel with TDT durations 0-4, as
  Parakeet-TDT);
- fastconformer-ctc: a plain FastConformer CTC model (EncDecCTCModelBPE).

Their output layers are scaled up and their blanks biased, so that near-ties decide nothing and
blanks and emissions mix. Prints each engine's real-time factor on these models too. The exported
directories are left under /tmp/speech_event_parity_*.
"""

import dataclasses
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, Dict, List, Tuple

import numpy as np

from bench.parity.random_nemo import (
    biased,
    conformer_rnnt,
    fastconformer_ctc,
    fastconformer_hybrid,
    fastconformer_tdt,
    tokenizer_directory,
)
from bench.parity.sentences import PARITY_SENTENCES, parity_audio
from speech_event.exporters.nemo import export
from speech_event.recognizers.nemo.ctc import ctc_greedy
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.nemo.vocabulary import load_vocabulary


@dataclasses.dataclass(frozen=True)
class Case:
    """A model to build, and the heads of it to export and compare."""

    build: Callable[[Path], Any]
    heads: Tuple[str, ...] = ("rnnt",)


CASES: Dict[str, Case] = {
    "conformer-rnnt": Case(conformer_rnnt),
    "fastconformer-hybrid": Case(fastconformer_hybrid, ("rnnt", "ctc")),
    "fastconformer-tdt": Case(fastconformer_tdt),
    "fastconformer-ctc": Case(fastconformer_ctc, ("ctc",)),
}


def _nemo_hypotheses(model: Any, audio: List[np.ndarray], head: str) -> List[Any]:
    """NeMo's own transcription (its preprocessor, encoder and default greedy decoding)."""
    if hasattr(model, "ctc_decoder"):  # a hybrid model: the head asked for
        model.change_decoding_strategy(decoder_type=head, verbose=False)
    hypotheses = model.transcribe(audio, batch_size=1, return_hypotheses=True, verbose=False)
    if isinstance(hypotheses, tuple):  # older NeMo: (best, all)
        hypotheses = hypotheses[0]
    return list(hypotheses)


def _nemo_tokens(hypothesis: Any, blank: int) -> List[int]:
    sequence = hypothesis.y_sequence
    if getattr(sequence, "ndim", 1) == 2:
        # CTC: NeMo's hypothesis keeps the frames' log-probabilities, its greedy decoding their best
        # tokens with repeats merged and blanks dropped (its text, compared too, is that decoding's)
        return ctc_greedy(np.asarray(sequence), blank).tokens
    return [int(token) for token in sequence]


def _compare(name: str, exported: Path, hypotheses: List[Any], audio: List[np.ndarray]) -> bool:
    engine = NemoRecognizer(exported)
    blank = load_vocabulary(exported / "vocab.txt").blank
    matches, worst_confidence = 0, 0.0
    busy = seconds = 0.0
    for sentence, samples, theirs in zip(PARITY_SENTENCES, audio, hypotheses):
        started = time.perf_counter()
        ours = engine.hypothesis(samples)
        busy += time.perf_counter() - started
        seconds += samples.size / 16000
        tokens = _nemo_tokens(theirs, blank)
        same = ours.tokens == tokens and engine.transcribe(samples).text == theirs.text
        matches += same
        difference = abs(ours.confidence - float(np.exp(float(theirs.score))))
        worst_confidence = max(worst_confidence, difference)
        print(
            f"  {sentence!r}: {'same' if same else 'DIFFERENT'} ({len(tokens)} tokens from NeMo; "
            f"confidence {ours.confidence:.4g}, NeMo's {np.exp(float(theirs.score)):.4g})"
        )
    print(
        f"{name}: {matches} of {len(PARITY_SENTENCES)} utterances give NeMo's own tokens and text; ", end=""
    )
    print(
        f"confidence differs by {worst_confidence:.2g} at most; engine RTF {busy / seconds:.3f}", flush=True
    )
    return matches == len(PARITY_SENTENCES)


def main(names: List[str]) -> int:
    import torch

    work = Path(tempfile.mkdtemp(prefix="speech_event_parity_"))
    tokenizer = tokenizer_directory(work)
    audio = parity_audio()
    all_same = True
    for name in names or list(CASES):
        torch.manual_seed(0)
        case = CASES[name]
        model = case.build(tokenizer)
        biased(model)
        model.eval()
        parameters = sum(p.numel() for p in model.parameters())
        nemo_file = work / f"{name}.nemo"
        model.save_to(str(nemo_file))
        for head in case.heads:
            exported = work / f"{name}-{head}"
            start = time.perf_counter()
            manifest = export(nemo_file, exported, head)
            print(
                f"{name} ({head} head): {parameters / 1e6:.1f} M parameters, exported in "
                f"{time.perf_counter() - start:.1f} s as {manifest.family}, {manifest.decoding}, "
                f"subsampling {manifest.subsampling_factor}, to {exported}"
            )
            all_same &= _compare(f"{name} ({head})", exported, _nemo_hypotheses(model, audio, head), audio)
    return 0 if all_same else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
