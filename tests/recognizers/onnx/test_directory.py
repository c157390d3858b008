"""Which of a model directory's ONNX files an engine runs (onnx/directory.py's Runtime): the fp32
file or its int8 version, by the quantization key and by what is there; and how it is opened."""

import platform
from pathlib import Path
from typing import List

import pytest

from fixtures.whisper_tones_model import whisper_tones_model_directory
from speech_event.errors import ModelError
from speech_event.recognizers.onnx import session as session_module
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.onnx.session import open_session

NONE, INT8 = Runtime(), Runtime(int8=True)
FP32, QUANTIZED = "encoder-model.onnx", "encoder-model.int8.onnx"


@pytest.mark.parametrize(
    ("files", "runtime", "chosen"),
    [
        pytest.param([FP32, QUANTIZED], NONE, FP32, id="fp32_where_both"),
        pytest.param([QUANTIZED], NONE, QUANTIZED, id="int8_where_only_it"),
        pytest.param([FP32], NONE, FP32, id="fp32_where_only_it"),
        pytest.param([], NONE, FP32, id="the_fp32_name_where_none_for_the_missing_file_error"),
        pytest.param([FP32, QUANTIZED], INT8, QUANTIZED, id="int8_asked"),
        pytest.param(["encoder-model_int8.onnx"], INT8, "encoder-model_int8.onnx", id="optimums_int8_name"),
    ],
)
def test_the_file_run(tmp_path: Path, files: List[str], runtime: Runtime, chosen: str) -> None:
    for name in files:
        (tmp_path / name).write_bytes(b"")
    assert runtime.model_file(tmp_path, FP32) == tmp_path / chosen


def test_int8_asked_where_there_is_none_says_how_to_get_it(tmp_path: Path) -> None:
    (tmp_path / "decoder.onnx").write_bytes(b"")
    with pytest.raises(ModelError) as error:
        INT8.model_file(tmp_path, "decoder.onnx")
    assert str(error.value) == (
        f"{tmp_path}: quantization is int8 but there is no int8 version of decoder.onnx (decoder.int8.onnx): "
        "export with --int8, pull with --int8, or set quantization none"
    )


def test_sessions_run_without_a_memory_pattern_but_with_the_arena_and_their_weights_outside_it() -> None:
    # the pattern keeps the largest utterance's plan for the process's life; the arena makes runs
    # fast, but rounds the weights' blocks up (speech_event/recognizers/onnx/session.py)
    session = open_session(whisper_tones_model_directory() / "encoder.onnx", ["CPUExecutionProvider"], "")
    options = session.get_session_options()
    assert (options.enable_mem_pattern, options.enable_cpu_mem_arena) == (False, True)
    assert options.get_session_config_entry("session.use_device_allocator_for_initializers") == "1"


def test_each_loaded_model_gives_the_heap_its_parsing_freed_back(monkeypatch: pytest.MonkeyPatch) -> None:
    assert (session_module._TRIM_HEAP is not None) == (platform.libc_ver()[0] == "glibc")
    trimmed: List[int] = []

    def trim(pad: int) -> int:
        trimmed.append(pad)
        return 1

    monkeypatch.setattr(session_module, "_TRIM_HEAP", trim)
    open_session(whisper_tones_model_directory() / "encoder.onnx", ["CPUExecutionProvider"], "")
    open_session(whisper_tones_model_directory() / "decoder.onnx", ["CPUExecutionProvider"], "")
    assert trimmed == [0, 0]
