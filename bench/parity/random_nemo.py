"""Randomly initialised NeMo models of realistic size with a small SentencePiece tokenizer: what
nemo_parity.py checks the engine against, and what bench/tools/family_models.py exports for the
speed and memory figures. Needs torch, nemo_toolkit and sentencepiece (imported when a model is built).

Random weights give flat logits, so each output layer is scaled up (near-ties must not decide the
result) and the blank biased so that blanks and emissions mix (``biased``)."""

from pathlib import Path
from typing import Any, Dict

from bench.parity.sentences import PARITY_SENTENCES
from fixtures.nemo_config import PREPROCESSOR

JOINT_OUTPUT_SCALE = 50.0
# Scaled random logits always beat the blank; this bias on the blank makes blanks and emissions
# mix, so the parity covers both paths of the decoding loop (and the max_symbols cap).
BLANK_BIAS = 25.0
CTC_BLANK_BIAS = 12.0
DURATIONS = [0, 1, 2, 3, 4]


def tokenizer_directory(directory: Path) -> Path:
    """``directory`` with a 48-piece SentencePiece BPE tokenizer trained on PARITY_SENTENCES and its
    vocab.txt: what a NeMo model's tokenizer config points at."""
    import sentencepiece

    corpus = directory / "corpus.txt"
    corpus.write_text("\n".join(PARITY_SENTENCES * 20))
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


def nemo_config(tokenizer: Path, fast: bool, tdt: bool = False, hybrid: bool = False) -> Dict[str, Any]:
    """A transducer's config on the large encoder (``fast``: FastConformer), with TDT durations or an
    auxiliary CTC head when asked: what the builders below and family_models.py build from."""
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


def conformer_rnnt(tokenizer: Path) -> Any:
    """The conformer-transducer large."""
    from nemo.collections.asr.models import EncDecRNNTBPEModel
    from omegaconf import OmegaConf

    return EncDecRNNTBPEModel(cfg=OmegaConf.create(nemo_config(tokenizer, fast=False)))


def fastconformer_hybrid(tokenizer: Path) -> Any:
    """A FastConformer hybrid RNN-T/CTC, as the robot loads Parakeet."""
    from nemo.collections.asr.models import EncDecHybridRNNTCTCBPEModel
    from omegaconf import OmegaConf

    return EncDecHybridRNNTCTCBPEModel(cfg=OmegaConf.create(nemo_config(tokenizer, fast=True, hybrid=True)))


def fastconformer_tdt(tokenizer: Path) -> Any:
    """A FastConformer TDT (durations 0-4), as Parakeet-TDT."""
    from nemo.collections.asr.models import EncDecRNNTBPEModel
    from omegaconf import OmegaConf

    return EncDecRNNTBPEModel(cfg=OmegaConf.create(nemo_config(tokenizer, fast=True, tdt=True)))


def fastconformer_ctc(tokenizer: Path) -> Any:
    """A plain FastConformer CTC model."""
    from nemo.collections.asr.models import EncDecCTCModelBPE
    from omegaconf import OmegaConf

    config = nemo_config(tokenizer, fast=True)
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


def biased(model: Any) -> None:
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
