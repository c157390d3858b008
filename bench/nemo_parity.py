"""Parity of the engine with NeMo itself (a tool, not CI): needs torch and nemo_toolkit.

    python3 -m venv /tmp/nemo && /tmp/nemo/bin/pip install torch==2.13.0 "nemo_toolkit[asr]"
    PYTHONPATH=. /tmp/nemo/bin/python -m bench.nemo_parity

Builds a randomly initialised NeMo conformer-transducer of the large configuration (17 blocks,
d_model 512) with a small SentencePiece tokenizer, saves it as .nemo, exports it with
``speech-event export-nemo`` (NeMo's own exporter underneath), and checks that the engine's tokens
equal NeMo's own greedy transcription of the same model on 10 audio files. Random weights give
flat logits, so the joint's output layer is scaled up: near-ties must not decide the result.
Also prints the engine's real-time factor on this large-size model.
"""

import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, List

import numpy as np

from fixtures.nemo_config import PREPROCESSOR
from fixtures.tts import speak_tts
from speech_event.asr.engine import NemoTransducerRecognizer
from speech_event.asr.export_nemo import export

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


def _large_config(tokenizer: Path) -> Dict[str, Any]:
    return {
        "sample_rate": 16000,
        "labels": None,
        "model_defaults": {"enc_hidden": 512, "pred_hidden": 640, "joint_hidden": 640},
        "tokenizer": {"dir": str(tokenizer), "type": "bpe"},
        "preprocessor": PREPROCESSOR,
        "spec_augment": None,
        "encoder": {
            "_target_": "nemo.collections.asr.modules.ConformerEncoder",
            "feat_in": 80,
            "feat_out": -1,
            "n_layers": 17,
            "d_model": 512,
            "subsampling": "striding",
            "subsampling_factor": 4,
            "subsampling_conv_channels": -1,
            "ff_expansion_factor": 4,
            "self_attention_model": "rel_pos",
            "n_heads": 8,
            "att_context_size": [-1, -1],
            "xscaling": True,
            "untie_biases": True,
            "pos_emb_max_len": 5000,
            "conv_kernel_size": 31,
            "conv_norm_type": "batch_norm",
            "dropout": 0.0,
            "dropout_pre_encoder": 0.0,
            "dropout_emb": 0.0,
            "dropout_att": 0.0,
        },
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
        "decoding": {"strategy": "greedy", "greedy": {"max_symbols": 10}},
        "loss": {"loss_name": "default"},
        "optim": None,
    }


def _as_16_bit(audio: np.ndarray) -> np.ndarray:
    """Audio as a 16-bit recording would give it back."""
    pcm: np.ndarray = np.round(np.clip(audio, -1, 1) * 32767).astype(np.int16)
    return pcm.astype(np.float32) / 32768.0


def _nemo_greedy_tokens(model: Any, samples: np.ndarray) -> List[int]:
    """NeMo's own preprocessor, encoder and greedy RNN-T decoding (what transcribe() runs)."""
    import torch

    with torch.no_grad():
        signal = torch.tensor(samples, dtype=torch.float32)[None]
        length = torch.tensor([samples.size])
        features, feature_length = model.preprocessor(input_signal=signal, length=length)
        encoded, encoded_length = model.encoder(audio_signal=features, length=feature_length)
        hypotheses = model.decoding.rnnt_decoder_predictions_tensor(
            encoder_output=encoded, encoded_lengths=encoded_length, return_hypotheses=True
        )
    if isinstance(hypotheses, tuple):  # older NeMo: (best, all)
        hypotheses = hypotheses[0]
    return [int(token) for token in hypotheses[0].y_sequence]


def main() -> int:
    import torch
    from nemo.collections.asr.models import EncDecRNNTBPEModel
    from omegaconf import OmegaConf

    torch.manual_seed(0)
    work = Path(tempfile.mkdtemp(prefix="speech_event_parity_"))
    model = EncDecRNNTBPEModel(cfg=OmegaConf.create(_large_config(_tokenizer(work))))
    with torch.no_grad():
        output_layer = model.joint.joint_net[-1]
        output_layer.weight.mul_(JOINT_OUTPUT_SCALE)
        output_layer.bias[-1] += BLANK_BIAS
    model.eval()
    parameters = sum(p.numel() for p in model.parameters())
    nemo_file = work / "random_large.nemo"
    model.save_to(str(nemo_file))
    start = time.perf_counter()
    export(nemo_file, work / "exported")
    print(f"model: {parameters / 1e6:.1f} M parameters; exported in {time.perf_counter() - start:.1f} s")

    engine = NemoTransducerRecognizer(work / "exported")
    audio = [_as_16_bit(speak_tts(sentence, 16000)) for sentence in SENTENCES]
    matches = 0
    busy = seconds = 0.0
    for sentence, samples in zip(SENTENCES, audio):
        theirs = _nemo_greedy_tokens(model, samples)
        started = time.perf_counter()
        ours = engine.token_ids(samples)
        busy += time.perf_counter() - started
        seconds += samples.size / 16000
        matches += ours == theirs
        frames = int(np.ceil(samples.size / 160 / 4))
        verdict = "same" if ours == theirs else "DIFFERENT"
        print(f"{sentence!r}: {verdict} ({len(theirs)} tokens from NeMo, about {frames} encoder frames)")
    print(f"parity: {matches} of {len(SENTENCES)} utterances give NeMo's own tokens")
    print(f"engine RTF on the large-size random model: {busy / seconds:.3f} ({seconds:.1f} s of audio)")
    return 0 if matches == len(SENTENCES) else 1


if __name__ == "__main__":
    sys.exit(main())
