"""Parity of the engine with NeMo itself (a tool, not CI): needs torch and nemo_toolkit.

    python3 -m venv /tmp/nemo && /tmp/nemo/bin/pip install torch==2.13.0 "nemo_toolkit[asr]"
    PYTHONPATH=. /tmp/nemo/bin/python -m bench.parity.nemo_parity [NAME ...]  # default: every model below

Builds randomly initialised NeMo models of realistic size with a small SentencePiece tokenizer,
saves each as .nemo, exports it with ``speech-event export-nemo`` (NeMo's own exporter underneath)
and checks that the engine gives NeMo's own transcription (``model.transcribe``, its default
greedy_batch decoding) of the same model on 10 utterances: the same tokens, and the confidence
(exp of NeMo's hypothesis score). The models:

- conformer-rnnt: the conformer-transducer large (17 blocks, d_model 512, 4x striding);
- fastconformer-hybrid: a FastConformer hybrid RNN-T/CTC (EncDecHybridRNNTCTCBPEModel, as the
  robot loads Parakeet; 17 blocks, d_model 512, 8x depthwise striding), both heads exported;
- fastconformer-tdt: a FastConformer TDT (EncDecRNNTBPEModel with TDT durations 0-4, as
  Parakeet-TDT);
- fastconformer-ctc: a plain FastConformer CTC model (EncDecCTCModelBPE).

Random weights give flat logits, so each output layer is scaled up (near-ties must not decide the
result) and the blank biased so that blanks and emissions mix. Prints each engine's real-time
factor on these models too. The exported directories are left under /tmp/speech_event_parity_*.
"""

import dataclasses
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, Dict, List, Tuple

import numpy as np

from fixtures.nemo_config import PREPROCESSOR
from fixtures.tts import speak_tts
from speech_event.exporters.nemo import export
from speech_event.recognizers.nemo.ctc import ctc_greedy
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.nemo.vocabulary import load_vocabulary

SENTENCES = [
    "go to the kitchen",
    "turn left",
    "stop",
    "bring me the red cup",
    "hello pepper",
    "what time is it",
    "open the door",
    "thank you very much",
    "follow me please",
    "good morning",
]
JOINT_OUTPUT_SCALE = 50.0
# Scaled random logits always beat the blank; this bias on the blank makes blanks and emissions
# mix, so the parity covers both paths of the decoding loop (and the max_symbols cap).
BLANK_BIAS = 25.0
CTC_BLANK_BIAS = 12.0
DURATIONS = [0, 1, 2, 3, 4]


def _tokenizer(directory: Path) -> Path:
    import sentencepiece

    corpus = directory / "corpus.txt"
    corpus.write_text("\n".join(SENTENCES * 20))
    sentencepiece.SentencePieceTrainer.train(
        input=str(corpus),
        model_prefix=str(directory / "tokenizer"),
        vocab_size=48,
        model_type="bpe",
        character_coverage=1.0,
        bos_id=-1,
        eos_id=-1,
    )
    pieces = [line.split("\t")[0] for line in (directory / "tokenizer.vocab").read_text().splitlines()]
    (directory / "vocab.txt").write_text("\n".join(pieces) + "\n")
    return directory


def _encoder(fast: bool) -> Dict[str, Any]:
    """The large encoder: Conformer (4x striding, kernel 31) or FastConformer (8x depthwise
    striding, kernel 9)."""
    return {
        "_target_": "nemo.collections.asr.modules.ConformerEncoder",
        "feat_in": 80,
        "feat_out": -1,
        "n_layers": 17,
        "d_model": 512,
        "subsampling": "dw_striding" if fast else "striding",
        "subsampling_factor": 8 if fast else 4,
        "subsampling_conv_channels": 256 if fast else -1,
        "causal_downsampling": False,
        "ff_expansion_factor": 4,
        "self_attention_model": "rel_pos",
        "n_heads": 8,
        "att_context_size": [-1, -1],
        "xscaling": True,
        "untie_biases": True,
        "pos_emb_max_len": 5000,
        "conv_kernel_size": 9 if fast else 31,
        "conv_norm_type": "batch_norm",
        "dropout": 0.0,
        "dropout_pre_encoder": 0.0,
        "dropout_emb": 0.0,
        "dropout_att": 0.0,
    }


def _config(tokenizer: Path, fast: bool, tdt: bool = False, hybrid: bool = False) -> Dict[str, Any]:
    decoding: Dict[str, Any] = {"strategy": "greedy_batch", "greedy": {"max_symbols": 10}}
    config: Dict[str, Any] = {
        "sample_rate": 16000,
        "labels": None,
        "model_defaults": {"enc_hidden": 512, "pred_hidden": 640, "joint_hidden": 640},
        "tokenizer": {"dir": str(tokenizer), "type": "bpe"},
        "preprocessor": PREPROCESSOR,
        "spec_augment": None,
        "encoder": _encoder(fast),
        "decoder": {
            "_target_": "nemo.collections.asr.modules.RNNTDecoder",
            "normalization_mode": None,
            "random_state_sampling": False,
            "blank_as_pad": True,
            "prednet": {"pred_hidden": 640, "pred_rnn_layers": 1, "t_max": None, "dropout": 0.0},
        },
        "joint": {
            "_target_": "nemo.collections.asr.modules.RNNTJoint",
            "log_softmax": None,
            "preserve_memory": False,
            "fuse_loss_wer": False,
            "jointnet": {"joint_hidden": 640, "activation": "relu", "dropout": 0.0},
        },
        "decoding": decoding,
        "loss": {"loss_name": "default"},
        "optim": None,
    }
    if tdt:
        config["model_defaults"].update(tdt_durations=DURATIONS, num_tdt_durations=len(DURATIONS))
        config["joint"]["num_extra_outputs"] = len(DURATIONS)
        config["loss"] = {
            "loss_name": "tdt",
            "tdt_kwargs": {"durations": DURATIONS, "sigma": 0.02, "omega": 0.1},
        }
        decoding.update(model_type="tdt", durations=DURATIONS)
    if hybrid:
        config["aux_ctc"] = {
            "ctc_loss_weight": 0.3,
            "use_cer": False,
            "ctc_reduction": "mean_batch",
            "decoder": {
                "_target_": "nemo.collections.asr.modules.ConvASRDecoder",
                "feat_in": None,
                "num_classes": -1,
                "vocabulary": [],
            },
            "decoding": {"strategy": "greedy_batch"},
        }
    return config


def _as_16_bit(audio: np.ndarray) -> np.ndarray:
    """Audio as a 16-bit recording would give it back."""
    pcm: np.ndarray = np.round(np.clip(audio, -1, 1) * 32767).astype(np.int16)
    return pcm.astype(np.float32) / 32768.0


@dataclasses.dataclass(frozen=True)
class Case:
    """A model to build, and the heads of it to export and compare."""

    build: Callable[[Path], Any]
    heads: Tuple[str, ...] = ("rnnt",)


def _conformer_rnnt(tokenizer: Path) -> Any:
    from nemo.collections.asr.models import EncDecRNNTBPEModel
    from omegaconf import OmegaConf

    return EncDecRNNTBPEModel(cfg=OmegaConf.create(_config(tokenizer, fast=False)))


def _fastconformer_hybrid(tokenizer: Path) -> Any:
    from nemo.collections.asr.models import EncDecHybridRNNTCTCBPEModel
    from omegaconf import OmegaConf

    return EncDecHybridRNNTCTCBPEModel(cfg=OmegaConf.create(_config(tokenizer, fast=True, hybrid=True)))


def _fastconformer_tdt(tokenizer: Path) -> Any:
    from nemo.collections.asr.models import EncDecRNNTBPEModel
    from omegaconf import OmegaConf

    return EncDecRNNTBPEModel(cfg=OmegaConf.create(_config(tokenizer, fast=True, tdt=True)))


def _fastconformer_ctc(tokenizer: Path) -> Any:
    from nemo.collections.asr.models import EncDecCTCModelBPE
    from omegaconf import OmegaConf

    config = _config(tokenizer, fast=True)
    for transducer_part in ("joint", "loss"):
        del config[transducer_part]
    config["decoder"] = {
        "_target_": "nemo.collections.asr.modules.ConvASRDecoder",
        "feat_in": 512,
        "num_classes": -1,
        "vocabulary": [],
    }
    config["decoding"] = {"strategy": "greedy_batch"}
    return EncDecCTCModelBPE(cfg=OmegaConf.create(config))


CASES: Dict[str, Case] = {
    "conformer-rnnt": Case(_conformer_rnnt),
    "fastconformer-hybrid": Case(_fastconformer_hybrid, ("rnnt", "ctc")),
    "fastconformer-tdt": Case(_fastconformer_tdt),
    "fastconformer-ctc": Case(_fastconformer_ctc, ("ctc",)),
}


def _biased(model: Any) -> None:
    """Scale the output layers up and bias their blanks (the blank is the last token, before TDT's
    durations)."""
    import torch

    with torch.no_grad():
        if hasattr(model, "joint"):
            output_layer = model.joint.joint_net[-1]
            output_layer.weight.mul_(JOINT_OUTPUT_SCALE)
            output_layer.bias[model.joint.num_classes_with_blank - 1] += BLANK_BIAS
        ctc_decoder = getattr(model, "ctc_decoder", None) or (
            None if hasattr(model, "joint") else model.decoder
        )
        if ctc_decoder is not None:
            ctc_layer = ctc_decoder.decoder_layers[0]
            ctc_layer.weight.mul_(JOINT_OUTPUT_SCALE)
            ctc_layer.bias[-1] += CTC_BLANK_BIAS


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
    for sentence, samples, theirs in zip(SENTENCES, audio, hypotheses):
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
    print(f"{name}: {matches} of {len(SENTENCES)} utterances give NeMo's own tokens and text; ", end="")
    print(
        f"confidence differs by {worst_confidence:.2g} at most; engine RTF {busy / seconds:.3f}", flush=True
    )
    return matches == len(SENTENCES)


def main(names: List[str]) -> int:
    import torch

    work = Path(tempfile.mkdtemp(prefix="speech_event_parity_"))
    tokenizer = _tokenizer(work)
    audio = [_as_16_bit(speak_tts(sentence, 16000)) for sentence in SENTENCES]
    all_same = True
    for name in names or list(CASES):
        torch.manual_seed(0)
        case = CASES[name]
        model = case.build(tokenizer)
        _biased(model)
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
