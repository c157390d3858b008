"""int8 on the CPUs robots have: python -m bench.figures.int8_cpus [--models tiny.en base] [--no-avx2]
[--all-schemes | --export-scheme-only] [--cards-only] [--qemu].

onnxruntime picks its int8 matrix kernels by CPU: AVX2's kernel for unsigned activations by signed
weights adds pairs of products in 16 bits and can saturate; AVX-512 VNNI's does not. This writes
trained Whisper's int8 files in each Int8Scheme (speech_event/exporters/quantize.py), transcribes
Debian's recordings of people (pocketsphinx-testdata: five cards phrases, five librivox sentences)
with each, on this CPU and as an AVX2 CPU without AVX-512 (bench/tools/avx2_cpu.py: natively, CPUID
answered without AVX-512; or with ``--qemu`` Debian's qemu-user running this Python as a Haswell,
``apt-get install qemu-user``, 50 to 100 times slower), and prints the word error rate of each and
how many texts differ between the two CPUs. base needs ``pip install '.[bench]'``.

Measured figures: docs/models.md#int8-on-every-cpu.
"""

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List

from bench.tools import avx2_cpu
from fixtures import recordings
from fixtures.trained_weights import BASE, TINY_EN, TrainedWhisper
from fixtures.trained_whisper import model_directory
from speech_event.exporters.quantize import SIGNED_PER_TENSOR, Int8Scheme, quantize_directory
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

MODELS: Dict[str, TrainedWhisper] = {"tiny.en": TINY_EN, "base": BASE}
SCHEMES: Dict[str, Int8Scheme] = {
    "7-bit, per channel (export --int8)": Int8Scheme(),
    "8-bit, per tensor (until 2026-11-28)": SIGNED_PER_TENSOR,
    "8-bit, per channel": Int8Scheme(seven_bits=False),
    "7-bit, per tensor": Int8Scheme(per_channel=False),
    "unsigned, per tensor": Int8Scheme(unsigned=True, per_channel=False, seven_bits=False),
    "unsigned, per channel": Int8Scheme(unsigned=True, seven_bits=False),
}
FP32_FILES = (
    "config.json",
    "tokens.txt",
    "encoder.onnx",
    "encoder.onnx.data",
    "decoder.onnx",
    "decoder.onnx.data",
)
# Haswell: AVX2 and FMA, no AVX-512 (qemu's v4 model of it, as the reference's measurements).
QEMU_HASWELL = ["qemu-x86_64", "-cpu", "Haswell-v4"]


def _recordings(cards_only: bool) -> List[recordings.Recording]:
    return recordings.cards() + ([] if cards_only else recordings.librivox())


def transcribe(directory: Path, int8: bool, cards_only: bool) -> List[str]:
    """Each recording's text by the Whisper engine on ``directory``."""
    engine = WhisperRecognizer(directory, "english", Runtime(int8=int8))
    return [engine.transcribe(recording.samples()).text for recording in _recordings(cards_only)]


def _on_avx2(directory: Path, cards_only: bool, qemu: bool) -> List[str]:
    """transcribe(directory, int8=True) in this Python run as an AVX2 CPU."""
    command = [sys.executable, "-m", "bench.figures.int8_cpus", "--transcribe", str(directory)]
    command += ["--cards-only"] if cards_only else []
    if qemu:
        done = subprocess.run([*QEMU_HASWELL, *command], capture_output=True, text=True, check=True)
    else:
        library = avx2_cpu.build(directory)
        done = subprocess.run(
            command, env=avx2_cpu.environment(library), capture_output=True, text=True, check=True
        )
    texts: List[str] = json.loads(done.stdout.splitlines()[-1])
    return texts


def _scheme_directory(fp32: Path, scheme: Int8Scheme, folder: Path) -> Path:
    """A copy of the fp32 files of ``fp32`` with int8 files written in ``scheme``."""
    folder.mkdir()
    for name in FP32_FILES:
        shutil.copy(fp32 / name, folder / name)
    quantize_directory(folder, scheme)
    return folder


def _wer(texts: List[str], cards_only: bool) -> float:
    references = " ".join(recording.text for recording in _recordings(cards_only))
    return recordings.word_error_rate(references, " ".join(texts))


def measure(
    name: str, avx2: bool, work: Path, schemes: Dict[str, Int8Scheme], cards_only: bool, qemu: bool
) -> None:
    fp32 = model_directory(MODELS[name])
    began = time.monotonic()
    texts = transcribe(fp32, False, cards_only)
    print(
        f"{name} fp32: WER {_wer(texts, cards_only):.3f} ({time.monotonic() - began:.1f} s here)", flush=True
    )
    for label, scheme in schemes.items():
        directory = _scheme_directory(
            fp32, scheme, work / f"{name}-{scheme.unsigned}-{scheme.per_channel}-{scheme.seven_bits}"
        )
        began = time.monotonic()
        here = transcribe(directory, True, cards_only)
        line = (
            f"{name} int8 {label}: WER here {_wer(here, cards_only):.3f} ({time.monotonic() - began:.1f} s)"
        )
        if avx2:
            began = time.monotonic()
            there = _on_avx2(directory, cards_only, qemu)
            differ = [f"{a!r} / {b!r}" for a, b in zip(here, there) if a != b]
            line += (
                f", as AVX2 {_wer(there, cards_only):.3f} ({time.monotonic() - began:.1f} s); "
                f"{len(differ)} of {len(here)} texts differ" + "".join(f"\n    {pair}" for pair in differ)
            )
        print(line, flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", choices=list(MODELS), default=["tiny.en"])
    parser.add_argument("--no-avx2", dest="avx2", action="store_false", help="only this CPU")
    parser.add_argument("--all-schemes", action="store_true", help="the six of docs/models.md, not two")
    parser.add_argument("--export-scheme-only", action="store_true", help="only what export --int8 writes")
    parser.add_argument(
        "--cards-only", action="store_true", help="the five cards recordings (a third of the time)"
    )
    parser.add_argument("--qemu", action="store_true", help="emulate the AVX2 CPU with qemu-user")
    parser.add_argument("--transcribe", type=Path, help=argparse.SUPPRESS)  # the emulated CPU's part
    arguments = parser.parse_args()
    if arguments.transcribe:
        print(json.dumps(transcribe(arguments.transcribe, True, arguments.cards_only)))
        return
    schemes = dict(
        list(SCHEMES.items())[: 1 if arguments.export_scheme_only else 6 if arguments.all_schemes else 2]
    )
    with tempfile.TemporaryDirectory(prefix="int8_cpus_") as work:
        for name in arguments.models:
            measure(name, arguments.avx2, Path(work), schemes, arguments.cards_only, arguments.qemu)


if __name__ == "__main__":
    main()
