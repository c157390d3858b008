"""The robot's model families at realistic size, random weights, exported by our tools, for
bench/figures/asr.py's speed and memory figures (a tool, not CI; needs torch, nemo_toolkit and
openai-whisper):

    PYTHONPATH=. /tmp/nemo/bin/python -m bench.tools.family_models OUT_DIR [NAME ...]

Writes OUT_DIR/conformer-large (NeMo's conformer-transducer large: 17 blocks, d_model 512),
OUT_DIR/parakeet-tdt-0.6b (FastConformer TDT shaped as Parakeet-TDT 0.6B: 24 blocks, d_model 1024,
8x depthwise striding, 128 mel bands, a 1024-token vocabulary), OUT_DIR/whisper-base and
OUT_DIR/whisper-small (Whisper's base and small shapes). The weights are random and biased as in
the parity benches, so decoding takes its usual paths; speed and memory do not depend on them.
"""

import sys
import tempfile
import time
from pathlib import Path
from typing import Callable, Dict, List

from bench.parity.random_nemo import biased, conformer_rnnt, nemo_config, tokenizer_directory
from bench.parity.sentences import PARITY_SENTENCES
from bench.parity.whisper_parity import random_checkpoint
from speech_event.exporters.nemo import export_model
from speech_event.exporters.whisper import export as export_whisper


def _tokenizer_of(size: int, work: Path) -> Path:
    import sentencepiece

    corpus = work / "corpus.txt"
    words = " ".join(PARITY_SENTENCES).split()
    # enough distinct text for a vocabulary of this size: every pair of words, spelled out
    corpus.write_text("\n".join(f"{a}{b} {b}{a} {a} {b}" for a in words for b in words))
    sentencepiece.SentencePieceTrainer.train(
        input=str(corpus),
        model_prefix=str(work / "tokenizer"),
        vocab_size=size,
        model_type="bpe",
        character_coverage=1.0,
        bos_id=-1,
        eos_id=-1,
        hard_vocab_limit=False,
    )
    pieces = [line.split("\t")[0] for line in (work / "tokenizer.vocab").read_text().splitlines()]
    (work / "vocab.txt").write_text("\n".join(pieces) + "\n")
    return work


def conformer_large(out: Path, work: Path) -> None:
    model = conformer_rnnt(tokenizer_directory(work))  # the parity bench's conformer-transducer large
    biased(model)
    export_model(model, out)


def parakeet_tdt_06b(out: Path, work: Path) -> None:
    from nemo.collections.asr.models import EncDecRNNTBPEModel
    from omegaconf import OmegaConf

    config = nemo_config(_tokenizer_of(1024, work), fast=True, tdt=True)
    config["preprocessor"] = {**config["preprocessor"], "features": 128}
    config["encoder"].update(feat_in=128, n_layers=24, d_model=1024)
    config["model_defaults"].update(enc_hidden=1024)
    model = EncDecRNNTBPEModel(cfg=OmegaConf.create(config))
    biased(model)
    export_model(model, out)


def whisper_shape(shape: str) -> Callable[[Path, Path], None]:
    def build(out: Path, work: Path) -> None:
        export_whisper(str(random_checkpoint(shape, work / f"{shape}.pt")), out, {})

    return build


MODELS: Dict[str, Callable[[Path, Path], None]] = {
    "conformer-large": conformer_large,
    "parakeet-tdt-0.6b": parakeet_tdt_06b,
    "whisper-base": whisper_shape("base"),
    "whisper-small": whisper_shape("small"),
}


def main(arguments: List[str]) -> int:
    import torch

    out = Path(arguments[0])
    for name in arguments[1:] or list(MODELS):
        torch.manual_seed(0)
        started = time.perf_counter()
        with tempfile.TemporaryDirectory() as work:
            MODELS[name](out / name, Path(work))
        print(f"{name}: exported to {out / name} in {time.perf_counter() - started:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
