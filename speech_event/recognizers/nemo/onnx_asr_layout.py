"""onnx-asr's NeMo model directories, loaded as they are (the exports published for onnx-asr, e.g.
istupakov/parakeet-tdt-0.6b-v2-onnx, and what its conversion guide writes).

Their ONNX files are NeMo's, as speech-event export-nemo writes them: ``encoder-model.onnx`` and
``decoder_joint-model.onnx`` (RNN-T, TDT) or ``model.onnx`` (CTC), weights of large models in
``*.onnx.data``, int8 files named ``encoder-model.int8.onnx``; and ``vocab.txt``. Their config.json
has onnx-asr's keys only (``model_type``, ``features_size``, ``subsampling_factor``,
``max_tokens_per_step``), or there is none. What our config.json records is derived from theirs
where ours is missing:

- the preprocessor: NeMo's (16 kHz, 25 ms windows every 10 ms, n_fft 512, pre-emphasis 0.97,
  per-feature normalisation) with ``features_size`` mel bands, 80 by default as in onnx-asr;
- the decoding: ``model_type``; without it, ``model.onnx`` is CTC, and a transducer is TDT when
  its joint gives more logits per step than ``vocab.txt`` has tokens, RNN-T when as many;
- TDT's durations: NeMo's default (0, 1, 2, 3, 4), unless the joint's logits say how many there
  are (logits = vocabulary + durations): then 0, 1, 2... as onnx-asr reads them;
- the family (manifest.py): parakeet for TDT and CTC, conformer-transducer for RNN-T;
- ``subsampling_factor`` (onnx-asr's default 8) and ``max_symbols_per_step`` from
  ``max_tokens_per_step`` (10 by default).

A config.json with ``sample_rate`` is speech-event export-nemo's: nothing is derived for it.
"""

from pathlib import Path
from typing import Any, Dict, Optional, Tuple

from speech_event.errors import ModelError
from speech_event.recognizers.nemo.onnx_files import (
    CTC_FILE,
    DECODER_JOINT_FILE,
    DECODER_OUTPUTS,
    ENCODER_FILE,
    NEMO_DIRECTORY,
)
from speech_event.recognizers.nemo.vocabulary import load_vocabulary
from speech_event.recognizers.onnx.directory import CPU_FP32, MANIFEST_FILE

# onnx-asr's names of the decodings (its model_type)
RNNT, TDT, CTC = "nemo-conformer-rnnt", "nemo-conformer-tdt", "nemo-conformer-ctc"
VOCABULARY_FILE = "vocab.txt"
NEMO_DEFAULT_DURATIONS = (0, 1, 2, 3, 4)
# NeMo's preprocessor at inference, as onnx-asr's nemo80 and nemo128 preprocessors compute it
NEMO_PREPROCESSOR: Dict[str, Any] = {
    "sample_rate": 16000,
    "window_size": 0.025,
    "window_stride": 0.01,
    "n_fft": 512,
    "preemph": 0.97,
    "normalize": "per_feature",
}
ONNX_ASR_FEATURES = 80  # onnx-asr's defaults when its config.json does not say
ONNX_ASR_SUBSAMPLING = 8
ONNX_ASR_MAX_TOKENS = 10


def is_ours(document: Dict[str, Any]) -> bool:
    """Whether config.json ``document`` is speech-event export-nemo's (it records the preprocessor)."""
    return "sample_rate" in document


def completed(document: Dict[str, Any], directory: Path) -> Dict[str, Any]:
    """config.json's ``document`` ({} without one) with what speech-event export-nemo records,
    derived from onnx-asr's keys and ``directory``'s files where missing. ModelError names the
    file or key missing when the directory cannot be understood."""
    if is_ours(document):
        return document
    decoding, extra = _decoding(document, directory)
    derived: Dict[str, Any] = {
        **NEMO_PREPROCESSOR,
        "features": document.get("features_size", ONNX_ASR_FEATURES),
        "model_type": decoding,
        "subsampling_factor": document.get("subsampling_factor", ONNX_ASR_SUBSAMPLING),
        "max_symbols_per_step": document.get("max_tokens_per_step", ONNX_ASR_MAX_TOKENS),
    }
    if decoding == TDT and "durations" not in document:
        count = extra if extra is not None else _extra_logits(directory)
        derived["durations"] = list(range(count) if count else NEMO_DEFAULT_DURATIONS)
    return {**derived, **document}


def decoding_of(document: Dict[str, Any], directory: Path) -> str:
    """The decoding config.json's ``document`` names; RNN-T for one of ours that does not (written
    before it was recorded); from the files for onnx-asr's without model_type. ModelError as completed."""
    if is_ours(document):
        return str(document.get("model_type", RNNT))
    return _decoding(document, directory)[0]


def _decoding(document: Dict[str, Any], directory: Path) -> Tuple[str, Optional[int]]:
    """onnx-asr's model_type, or the decoding of the files; and the joint's extra logits when read."""
    if "model_type" in document:
        return str(document["model_type"]), None
    present = {
        name: CPU_FP32.model_file(directory, name).is_file() for name in (ENCODER_FILE, DECODER_JOINT_FILE)
    }
    if any(present.values()):
        for name, there in present.items():
            if not there:
                raise ModelError(f"{directory}: missing {name}; {NEMO_DIRECTORY}")
        extra = _extra_logits(directory)
        if extra is None:
            joint = CPU_FP32.model_file(directory, DECODER_JOINT_FILE)
            raise ModelError(
                f"{joint}: its logits per step are not fixed in the file, "
                f"so RNN-T and TDT cannot be told apart: {MANIFEST_FILE} needs model_type "
                f"({RNNT} or {TDT})"
            )
        return (TDT if extra > 0 else RNNT), extra
    if CPU_FP32.model_file(directory, CTC_FILE).is_file():
        return CTC, None
    raise ModelError(f"{directory}: missing {MANIFEST_FILE} and the model's ONNX files; {NEMO_DIRECTORY}")


def _extra_logits(directory: Path) -> Optional[int]:
    """The joint's logits per step beyond the vocabulary's tokens (TDT's durations); None when the
    file does not fix its logits."""
    vocabulary = directory / VOCABULARY_FILE
    if not vocabulary.is_file():
        raise ModelError(f"{directory}: missing {VOCABULARY_FILE}; {NEMO_DIRECTORY}")
    # onnxruntime only now: the node imports this module without it
    from speech_event.recognizers.onnx.session import check_tensors, last_dimension, open_session

    path = CPU_FP32.model_file(directory, DECODER_JOINT_FILE)
    session = open_session(path, ["CPUExecutionProvider"], NEMO_DIRECTORY)
    check_tensors(path, "outputs", session.get_outputs(), DECODER_OUTPUTS, "a NeMo export")
    size = last_dimension(session, "outputs")
    return None if size is None else size - load_vocabulary(vocabulary).size
