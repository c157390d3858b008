"""int8 model files (speech_event/exporters/quantize.py) and the quantization key that picks them,
on the fixture models of each decoding: written beside the fp32 files under onnx-asr's names, their
matrix products int8, and the same texts as fp32 through the node's own engine builder."""

import logging
import shutil
from pathlib import Path
from typing import Callable, Dict, Iterator, List, Tuple

import onnx
import pytest

from fixtures.audio import speak_tones
from fixtures.tones_model import tones_ctc_model_directory, tones_model_directory, tones_tdt_model_directory
from fixtures.whisper_tones_model import whisper_tones_model_directory
from fixtures.whisper_tones_optimum import whisper_tones_optimum_directory
from speech_event.config import SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.exporters import nemo as nemo_exporter
from speech_event.exporters.quantize import quantize_directory
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.features import FeatureSettings
from speech_event.recognizers.nemo.manifest import Manifest

TRANSDUCER = ["decoder_joint-model.onnx", "encoder-model.onnx"]
# name: (the fixture model, its model family, its fp32 files, its matrix products by a weight)
MODELS: Dict[str, Tuple[Callable[[], Path], str, List[str], int]] = {
    "rnnt": (tones_model_directory, "conformer-transducer", TRANSDUCER, 3),
    "tdt": (tones_tdt_model_directory, "parakeet", TRANSDUCER, 3),
    "ctc": (tones_ctc_model_directory, "parakeet", ["model.onnx"], 1),
    # its one product by a weight has the weight on the left (templates x spectrum): none to quantize
    "whisper": (whisper_tones_model_directory, "whisper", ["decoder.onnx", "encoder.onnx"], 0),
    # optimum's layout: the merged decoder's output projection, once in each of its If's branches
    "whisper-optimum": (
        whisper_tones_optimum_directory,
        "whisper",
        ["decoder_model_merged.onnx", "encoder_model.onnx"],
        2,
    ),
}
PHRASES = ["go to the kitchen", "yes", "stop", "where is the door", "please open the window"]


def _copy(name: str, tmp_path: Path) -> Path:
    directory = tmp_path / name
    shutil.copytree(MODELS[name][0](), directory)
    return directory


def _transcribe(directory: Path, family: str, quantization: str) -> List[str]:
    config = SpeechEventConfig(model=family, en_model_path=str(directory), quantization=quantization)
    engine = RECOGNIZERS["auto"](config)
    return [engine.transcribe(speak_tones(phrase, 16000)).text for phrase in PHRASES]


def _nodes(graph: onnx.GraphProto) -> Iterator[onnx.NodeProto]:
    """The graph's nodes and those of the branches and bodies of its control-flow nodes."""
    for node in graph.node:
        yield node
        for attribute in node.attribute:
            for subgraph in [attribute.g] if attribute.HasField("g") else attribute.graphs:
                yield from _nodes(subgraph)


def _weight_products(path: Path) -> int:
    """MatMul nodes of the file whose right-hand side is a weight (an initializer: the subgraphs'
    products read the main graph's)."""
    graph = onnx.load(str(path)).graph
    weights = {initializer.name for initializer in graph.initializer}
    return sum(1 for node in _nodes(graph) if node.op_type == "MatMul" and node.input[1] in weights)


def _int8_products(path: Path) -> int:
    return sum(1 for node in _nodes(onnx.load(str(path)).graph) if node.op_type == "MatMulInteger")


@pytest.mark.parametrize("name", list(MODELS))
def test_each_fp32_file_gets_an_int8_file_of_onnx_asrs_name_with_int8_matrix_products(
    name: str, tmp_path: Path
) -> None:
    directory = _copy(name, tmp_path)
    fp32 = MODELS[name][2]
    written = quantize_directory(directory)
    assert [path.name for path in written] == [file.replace(".onnx", ".int8.onnx") for file in fp32]
    products = 0
    for before, after in zip(fp32, written):
        assert (directory / before).read_bytes() == (MODELS[name][0]() / before).read_bytes()
        assert (_int8_products(after), _weight_products(after)) == (_weight_products(directory / before), 0)
        products += _int8_products(after)
    assert products == MODELS[name][3]
    assert not list(directory.glob("*.partial"))


@pytest.mark.parametrize("name", list(MODELS))
def test_quantization_int8_runs_the_int8_files_and_they_say_what_fp32_says(name: str, tmp_path: Path) -> None:
    directory = _copy(name, tmp_path)
    _, family, fp32, _ = MODELS[name]
    said = _transcribe(directory, family, "none")
    quantize_directory(directory)
    for file in fp32:  # from here on, reading an fp32 file fails: int8 must be what runs
        (directory / file).write_bytes(b"not a model")
    assert _transcribe(directory, family, "int8") == said == PHRASES


def test_quantization_int8_without_int8_files_names_the_file_and_how_to_get_it(tmp_path: Path) -> None:
    directory = _copy("rnnt", tmp_path)
    with pytest.raises(ModelError) as error:
        _transcribe(directory, "conformer-transducer", "int8")
    assert str(error.value) == (
        f"{directory}: quantization is int8 but there is no int8 version of encoder-model.onnx "
        "(encoder-model.int8.onnx): export with --int8, pull with --int8, or set quantization none"
    )


def test_export_nemo_int8_quantizes_what_it_exported(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def export(nemo_path: Path, out_dir: Path, head: str, family: object) -> Manifest:
        """NeMo is not installed in CI: the fixture model stands for what NeMo exported."""
        shutil.copytree(tones_model_directory(), out_dir)
        return Manifest(FeatureSettings())

    monkeypatch.setattr(nemo_exporter, "export", export)
    out = tmp_path / "out"
    assert nemo_exporter.main(["m.nemo", str(out), "--int8"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        f"wrote {out} (conformer-transducer, nemo-conformer-rnnt): set model conformer-transducer, and rw_model_path or "
        "en_model_path to it",
        f"wrote {out / 'decoder_joint-model.int8.onnx'} (int8: set quantization int8 to use it)",
        f"wrote {out / 'encoder-model.int8.onnx'} (int8: set quantization int8 to use it)",
    ]


def test_quantizing_leaves_out_onnxruntimes_advice_and_nothing_else(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    directory = _copy("rnnt", tmp_path)
    with caplog.at_level(logging.WARNING):  # what a user sees (the quantizer's INFO is not shown)
        quantize_directory(directory)
        logging.warning("a warning of another kind")  # still said while quantizing is over
    assert [record.getMessage() for record in caplog.records if record.name == "root"] == [
        "a warning of another kind"
    ]
