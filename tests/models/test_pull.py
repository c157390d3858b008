"""``speech-event pull`` against a Hugging Face Hub of the test's own on 127.0.0.1: the file API that
huggingface_hub calls (model info with its files, the tree listing, and each file by HEAD and GET
with its commit, ETag and ranges), serving models the tests build. Each pull runs as the command
does, in a process of its own whose HF_ENDPOINT and HF_HOME point at the test's hub and folders.

A faster-whisper repository is the small CTranslate2 Whisper of fixtures/ct2_whisper_model.py:
pulled, it is export-whisper's directory byte for byte, and the engine decodes with it what
CTranslate2 (the ``ctranslate2`` package, test-only) decodes with the model.bin served."""

import hashlib
import json
import os
import subprocess
import sys
import threading
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple
from urllib.parse import unquote, urlsplit

import ctranslate2
import numpy as np
import onnx
import pytest

from fixtures import recordings
from fixtures.audio import noise, speak_tones
from fixtures.ct2_whisper_model import (
    EXPORTED_FILES,
    TEXT_POSITIONS,
    model_bin_bytes,
    tokenizer_json,
    write_whisper_directory,
)
from fixtures.transducer_model import build_random_transducer
from fixtures.whisper_tones_optimum import optimum_json_files, whisper_tones_optimum_directory
from speech_event.exporters import whisper as whisper_exporter
from speech_event.models.conversion import NO_KINYARWANDA, ONNX_MISSING
from speech_event.models.pull import KNOWN, main
from speech_event.pipeline.resample import resample
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.manifest import load_whisper_manifest
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

TDT_NAME = "nemo-parakeet-tdt-0.6b-v2"
TDT_REPOSITORY = KNOWN[TDT_NAME]
ONNX_ASR_TDT = {
    "model_type": "nemo-conformer-tdt",
    "features_size": 80,
    "subsampling_factor": 4,
    "max_tokens_per_step": 10,
}
SECONDS = 120  # at most, for one pull


class FakeHub(ThreadingHTTPServer):
    """Model repositories (path -> bytes) behind the Hub's file API; every request logged. One
    file's download can be cut off: once after half its bytes (``drop``), or held there until
    ``release`` (``hold``, which sets ``halfway``)."""

    daemon_threads = True
    block_on_close = False

    def __init__(self) -> None:
        super().__init__(("127.0.0.1", 0), _Handler)
        self.repositories: Dict[str, Dict[str, bytes]] = {}
        self.requests: List[Tuple[str, str, Optional[str]]] = []  # method, path, Range
        self.drop: Optional[str] = None
        self.hold: Optional[str] = None
        self.halfway = threading.Event()
        self.release = threading.Event()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.server_address[1]}"

    def downloads(self, name: str) -> int:
        """The GETs of file ``name`` of any repository."""
        return sum(1 for method, path, _ in self.requests if method == "GET" and path.endswith(f"/{name}"))

    def commit(self, repository: str) -> str:
        files = self.repositories[repository]
        return hashlib.sha1(b"".join(name.encode() + files[name] for name in sorted(files))).hexdigest()


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    server: FakeHub

    def log_message(self, format: str, *args: Any) -> None:
        pass

    def do_HEAD(self) -> None:
        self._answer(body=False)

    def do_GET(self) -> None:
        self._answer(body=True)

    def _send(self, status: int, headers: Dict[str, str], payload: bytes, body: bool) -> None:
        self.send_response(status)
        for key, value in {"Content-Length": str(len(payload)), **headers}.items():
            self.send_header(key, value)
        self.end_headers()
        if body:
            self.wfile.write(payload)

    def _json(self, value: object, body: bool) -> None:
        self._send(200, {"Content-Type": "application/json"}, json.dumps(value).encode(), body)

    def _answer(self, body: bool) -> None:
        hub = self.server
        hub.requests.append((self.command, self.path, self.headers.get("Range")))
        parts = unquote(urlsplit(self.path).path).strip("/").split("/")
        api = parts[:2] == ["api", "models"]
        repository = "/".join(parts[2:4] if api else parts[:2])
        files = hub.repositories.get(repository)
        if files is None:
            error = json.dumps({"error": "Repository not found"}).encode()
            self._send(404, {"X-Error-Code": "RepoNotFound", "Content-Type": "application/json"}, error, body)
        elif api and parts[4:5] == ["tree"]:
            tree = [
                {"type": "file", "path": name, "size": len(data), "oid": hashlib.sha1(data).hexdigest()}
                for name, data in sorted(files.items())
            ]
            self._json(tree, body)
        elif api:
            siblings = [{"rfilename": name} for name in sorted(files)]
            self._json(
                {
                    "id": repository,
                    "modelId": repository,
                    "sha": hub.commit(repository),
                    "private": False,
                    "siblings": siblings,
                },
                body,
            )
        elif parts[2:3] == ["resolve"]:
            self._file(repository, "/".join(parts[4:]), body)
        else:
            self._send(404, {}, b"", body)

    def _file(self, repository: str, name: str, body: bool) -> None:
        hub = self.server
        data = hub.repositories[repository].get(name)
        headers = {"X-Repo-Commit": hub.commit(repository)}
        if data is None:
            self._send(404, {**headers, "X-Error-Code": "EntryNotFound"}, b"", body)
            return
        headers.update(ETag=f'"{hashlib.sha256(data).hexdigest()}"', **{"Accept-Ranges": "bytes"})
        start = int(self.headers.get("Range", "bytes=0-")[len("bytes=") :].split("-")[0])
        if start:
            headers["Content-Range"] = f"bytes {start}-{len(data) - 1}/{len(data)}"
        if body and name in (hub.drop, hub.hold):
            # the whole file announced, half of it sent, then the connection gone
            self.send_response(200)
            self.send_header("Content-Length", str(len(data)))
            for key, value in headers.items():
                self.send_header(key, value)
            self.end_headers()
            self.wfile.write(data[: len(data) // 2])
            self.wfile.flush()
            if name == hub.hold:
                hub.halfway.set()
                hub.release.wait(SECONDS)
            hub.drop = None
            self.close_connection = True
            return
        self._send(206 if start else 200, headers, data[start:], body)


@pytest.fixture
def hub() -> Iterator[FakeHub]:
    server = FakeHub()
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield server
    finally:
        server.release.set()
        server.shutdown()
        server.server_close()
        thread.join(10)


def onnx_asr_tdt_repository(built: Path) -> Dict[str, bytes]:
    """A TDT model in the layout of istupakov's exports: fp32 files (the encoder's weights in
    encoder-model.onnx.data), int8 ones (here the same graphs under their names), vocab.txt,
    onnx-asr's config.json; and files the engine does not need."""
    model = build_random_transducer(built, seed=2, durations=(0, 1, 2, 3, 4))
    encoder = onnx.load(str(model / "encoder-model.onnx"))
    onnx.save(
        encoder,
        str(built / "external.onnx"),
        save_as_external_data=True,
        location="encoder-model.onnx.data",
        size_threshold=0,
    )
    return {
        "encoder-model.onnx": (built / "external.onnx").read_bytes(),
        "encoder-model.onnx.data": (built / "encoder-model.onnx.data").read_bytes(),
        "decoder_joint-model.onnx": (model / "decoder_joint-model.onnx").read_bytes(),
        "encoder-model.int8.onnx": (model / "encoder-model.onnx").read_bytes(),
        "decoder_joint-model.int8.onnx": (model / "decoder_joint-model.onnx").read_bytes(),
        "vocab.txt": (model / "vocab.txt").read_bytes(),
        "config.json": json.dumps(ONNX_ASR_TDT, indent=4).encode(),
        "nemo128.onnx": b"onnx-asr's preprocessor: not needed",
        "README.md": b"# a model card\n",
        ".gitattributes": b"*.onnx filter=lfs\n",
    }


@pytest.fixture(scope="module")
def tdt_files(tmp_path_factory: pytest.TempPathFactory) -> Dict[str, bytes]:
    return onnx_asr_tdt_repository(tmp_path_factory.mktemp("tdt"))


def pull(
    hub: FakeHub, home: Path, *arguments: str, without: Sequence[str] = ()
) -> "subprocess.CompletedProcess[str]":
    """``speech-event pull ARGUMENTS`` in a process of its own, on ``hub``, with its Hugging Face
    folders in ``home``; no proxy, no token, nothing else of the Hub's settings from outside.
    The packages ``without`` names cannot be imported in it, as when they are not installed."""
    return subprocess.run(
        [
            sys.executable,
            "-c",
            f"import sys; sys.modules.update(dict.fromkeys({list(without)!r})); "
            "from speech_event.application import main; sys.exit(main())",
            "pull",
            *arguments,
        ],
        env=_environment(hub, home),
        capture_output=True,
        text=True,
        timeout=SECONDS,
    )


def _environment(hub: FakeHub, home: Path) -> Dict[str, str]:
    outside = ("HF_", "HUGGING_FACE_", "HTTP_PROXY", "HTTPS_PROXY", "ALL_PROXY")
    environment = {key: value for key, value in os.environ.items() if not key.upper().startswith(outside)}
    environment.update(
        HF_ENDPOINT=hub.url,
        HF_HOME=str(home / "hf"),
        HF_HUB_CACHE=str(home / "hf" / "hub"),
        HF_HUB_DISABLE_TELEMETRY="1",
        NO_PROXY="127.0.0.1,localhost",
        no_proxy="127.0.0.1,localhost",
    )
    return environment


def _listing(directory: Path) -> Dict[str, bytes]:
    return {path.name: path.read_bytes() for path in sorted(directory.iterdir())}


def _audio() -> np.ndarray:
    return np.concatenate(
        [noise(16000, -30.0, np.random.default_rng(2)), resample(speak_tones("yego", 48000), 48000, 16000)]
    )


def test_a_known_name_is_pulled_with_only_the_files_the_engine_needs(
    hub: FakeHub, tmp_path: Path, tdt_files: Dict[str, bytes]
) -> None:
    hub.repositories[TDT_REPOSITORY] = tdt_files
    directory = tmp_path / "models" / "en"
    done = pull(hub, tmp_path, TDT_NAME, str(directory))
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"model parakeet\nen_model_path {directory}\n"
    wanted = [
        "config.json",
        "decoder_joint-model.onnx",
        "encoder-model.onnx",
        "encoder-model.onnx.data",
        "vocab.txt",
    ]
    assert _listing(directory) == {name: tdt_files[name] for name in wanted}
    for name in set(tdt_files) - set(wanted):
        assert hub.downloads(name) == 0
    assert not (tmp_path / "models" / ".en.partial").exists()
    # the directory the lines name runs, the encoder's weights read from its .onnx.data
    assert NemoRecognizer(directory).transcribe(_audio()).text != ""


def test_int8_takes_the_int8_files_and_kinyarwanda_its_key(
    hub: FakeHub, tmp_path: Path, tdt_files: Dict[str, bytes]
) -> None:
    hub.repositories["someone/parakeet-onnx"] = tdt_files
    directory = tmp_path / "rw"
    done = pull(hub, tmp_path, "someone/parakeet-onnx", str(directory), "--int8", "--language", "kinyarwanda")
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"model parakeet\nrw_model_path {directory}\n"
    wanted = ["config.json", "decoder_joint-model.int8.onnx", "encoder-model.int8.onnx", "vocab.txt"]
    assert _listing(directory) == {name: tdt_files[name] for name in wanted}
    assert hub.downloads("encoder-model.onnx") == hub.downloads("encoder-model.onnx.data") == 0
    assert NemoRecognizer(directory).transcribe(_audio()).text != ""


def test_a_whisper_repository_of_optimums_layout_is_pulled_flat_and_runs(
    hub: FakeHub, tmp_path: Path
) -> None:
    model = whisper_tones_optimum_directory()
    files = {
        "onnx/encoder_model_int8.onnx": (model / "encoder_model.onnx").read_bytes(),
        "onnx/decoder_model_merged_int8.onnx": (model / "decoder_model_merged.onnx").read_bytes(),
        "onnx/encoder_model.onnx": b"encoder fp32: not taken with --int8",
        "onnx/decoder_model_merged.onnx": b"decoder merged fp32",
        "onnx/decoder_model.onnx": b"decoder without the cache: not needed",
        **{name: (model / name).read_bytes() for name in optimum_json_files()},
        "merges.txt": b"#version: 0.2\n",
        "tokenizer.json": b"{}",
        "README.md": b"# whisper\n",
    }
    hub.repositories["onnx-community/whisper-base"] = files
    directory = tmp_path / "whisper"
    done = pull(hub, tmp_path, "whisper-base", str(directory), "--int8")
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"model whisper\nen_model_path {directory}\n"
    assert sorted(_listing(directory)) == [
        "added_tokens.json",
        "config.json",
        "decoder_model_merged_int8.onnx",
        "encoder_model_int8.onnx",
        "generation_config.json",
        "merges.txt",
        "tokenizer.json",
        "vocab.json",
    ]
    engine = WhisperRecognizer(directory, "english", Runtime(int8=True))
    assert engine.transcribe(speak_tones("go left", 16000)).text == "go left"


def test_a_whisper_repository_without_what_the_engine_reads_is_refused_and_left_out(
    hub: FakeHub, tmp_path: Path
) -> None:
    model = whisper_tones_optimum_directory()
    files = {name: (model / name).read_bytes() for name in (*optimum_json_files(), "encoder_model.onnx")}
    files["decoder_model_merged.onnx"] = (model / "decoder_model_merged.onnx").read_bytes()
    files["generation_config.json"] = b"{}"
    files["config.json"] = json.dumps(
        {"model_type": "whisper", "vocab_size": 63, "num_mel_bins": 80}
    ).encode()
    hub.repositories["someone/whisper"] = files
    directory = tmp_path / "whisper"
    done = pull(hub, tmp_path, "someone/whisper", str(directory))
    assert done.returncode == 2
    assert done.stderr.endswith(
        "error: someone/whisper: the files downloaded are not a model the engine loads: "
        f"{tmp_path}/.whisper.partial/config.json: no 'max_target_positions'; transformers' Whisper config has it\n"
    )
    assert not directory.exists() and not (tmp_path / ".whisper.partial").exists()


@dataclass(frozen=True)
class FasterWhisper:
    """A faster-whisper repository's files, the directory they were written from, and what
    export-whisper makes of that directory (fp32 and int8 files together)."""

    files: Dict[str, bytes]
    source: Path
    exported: Path


@pytest.fixture(scope="module")
def faster_whisper(tmp_path_factory: pytest.TempPathFactory) -> FasterWhisper:
    """The small CTranslate2 Whisper as Systran publishes tiny.en: model.bin in float16,
    config.json, CTranslate2's vocabulary.txt and Hugging Face's tokenizer.json, a card."""
    built = tmp_path_factory.mktemp("faster-whisper")
    source = write_whisper_directory(built / "source", "float16", "vocabulary.txt")
    files = {name: (source / name).read_bytes() for name in ("model.bin", "config.json", "vocabulary.txt")}
    files.update(
        {
            "tokenizer.json": json.dumps(tokenizer_json()).encode(),
            "README.md": b"# faster-whisper tiny.en\n",
            ".gitattributes": b"*.bin filter=lfs\n",
        }
    )
    exported = built / "exported"
    assert whisper_exporter.main([str(source), str(exported), "--int8"]) == 0
    return FasterWhisper(files, source, exported)


def _ctranslate2_tokens(model: FasterWhisper, audio: np.ndarray) -> List[int]:
    """CTranslate2's greedy decoding of ``audio`` with the faster-whisper directory, at the engine's
    precision and under Whisper's rules (no timestamps, config.json's suppressed tokens, blank
    suppressed at the start), given the engine's log-mel."""
    manifest = load_whisper_manifest(model.exported / "config.json")
    reference = ctranslate2.models.Whisper(str(model.source), compute_type="float32", intra_threads=1)
    result = reference.generate(
        ctranslate2.StorageView.from_array(whisper_log_mel(audio, manifest.mel_bands)[None]),
        [manifest.prompt("english")],
        beam_size=1,
        suppress_blank=True,
        suppress_tokens=[-1],
        max_length=TEXT_POSITIONS,
    )
    return list(result[0].sequences_ids[0])


def test_a_faster_whisper_repository_is_converted_into_the_engines_directory(
    hub: FakeHub, tmp_path: Path, faster_whisper: FasterWhisper
) -> None:
    hub.repositories["Systran/faster-whisper-tiny.en"] = faster_whisper.files
    directory = tmp_path / "models" / "en"
    done = pull(hub, tmp_path, "faster-whisper-tiny.en", str(directory))
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"model whisper\nen_model_path {directory}\n"
    assert done.stderr.splitlines()[-2:] == [
        "Systran/faster-whisper-tiny.en: converting to the Whisper engine's ONNX files",
        f"{directory}: a whisper model; its configuration lines:",
    ]
    # export-whisper's directory, and nothing of CTranslate2's: model.bin stays in the cache
    assert _listing(directory) == {
        name: (faster_whisper.exported / name).read_bytes() for name in EXPORTED_FILES
    }
    assert [hub.downloads(name) for name in faster_whisper.files] == [1, 1, 1, 0, 0, 0]
    assert [path.name for path in (tmp_path / "models").iterdir()] == ["en"]
    audio = recordings.cards()[0].samples()
    tokens = WhisperRecognizer(directory, "english").decode(audio).tokens
    assert tokens == _ctranslate2_tokens(faster_whisper, audio)
    assert len(tokens) == 12  # sample_len: the random model never ends its text


def test_int8_keeps_only_the_int8_graphs_of_a_faster_whisper_conversion(
    hub: FakeHub, tmp_path: Path, faster_whisper: FasterWhisper
) -> None:
    hub.repositories["someone/faster-whisper-base"] = faster_whisper.files
    directory = tmp_path / "en"
    done = pull(hub, tmp_path, "someone/faster-whisper-base", str(directory), "--int8")
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"model whisper\nen_model_path {directory}\n"
    assert (
        "someone/faster-whisper-base: converting to the Whisper engine's ONNX files and quantizing them to int8"
        in done.stderr.splitlines()
    )
    written = [
        "config.json",
        "decoder.int8.onnx",
        "decoder.int8.onnx.data",
        "encoder.int8.onnx",
        "encoder.int8.onnx.data",
        "tokens.txt",
    ]
    assert _listing(directory) == {name: (faster_whisper.exported / name).read_bytes() for name in written}
    # only int8 graphs: the engine runs them whatever quantization says
    audio = recordings.cards()[0].samples()
    assert WhisperRecognizer(directory, "english").decode(audio).tokens == (
        WhisperRecognizer(faster_whisper.exported, "english", Runtime(int8=True)).decode(audio).tokens
    )


FASTER_WHISPER_NEEDS = (
    "the engine needs model.bin, config.json and one of vocabulary.json, vocabulary.txt or tokenizer.json"
)


@pytest.mark.parametrize(
    ("removed", "changed", "arguments", "without", "message"),
    [
        (
            ["model.bin"],
            {},
            [],
            [],
            f"someone/faster-whisper is a faster-whisper (CTranslate2) Whisper model but has no model.bin: "
            f"{FASTER_WHISPER_NEEDS}",
        ),
        (
            ["vocabulary.txt", "tokenizer.json"],
            {},
            [],
            [],
            "someone/faster-whisper is a faster-whisper (CTranslate2) Whisper model but has none of "
            f"vocabulary.json, vocabulary.txt or tokenizer.json: {FASTER_WHISPER_NEEDS}",
        ),
        (
            [],
            # a CTranslate2 model of another kind: a translator's config
            {"config.json": json.dumps({"add_source_bos": False, "unk_token": "<unk>"}).encode()},
            [],
            [],
            "someone/faster-whisper: {snapshot}/config.json: no list of token ids 'suppress_ids'; "
            "CTranslate2's Whisper config has suppress_ids and suppress_ids_begin, which Whisper's decoding "
            "rules need",
        ),
        ([], {}, ["--language", "kinyarwanda"], [], f"someone/faster-whisper: {NO_KINYARWANDA}"),
        ([], {}, [], ["onnx"], f"someone/faster-whisper: {ONNX_MISSING}"),
    ],
    ids=["no-model-bin", "no-vocabulary", "not-whisper", "kinyarwanda", "no-onnx"],
)
def test_a_faster_whisper_repository_that_cannot_be_converted_is_refused_before_model_bin_is_fetched(
    hub: FakeHub,
    tmp_path: Path,
    faster_whisper: FasterWhisper,
    removed: List[str],
    changed: Dict[str, bytes],
    arguments: List[str],
    without: List[str],
    message: str,
) -> None:
    files = {name: data for name, data in faster_whisper.files.items() if name not in removed}
    hub.repositories["someone/faster-whisper"] = {**files, **changed}
    done = pull(hub, tmp_path, "someone/faster-whisper", str(tmp_path / "model"), *arguments, without=without)
    snapshot = tmp_path / "hf" / "hub" / "models--someone--faster-whisper" / "snapshots"
    expected = message.format(snapshot=snapshot / hub.commit("someone/faster-whisper"))
    assert (done.returncode, done.stdout, done.stderr) == (2, "", f"error: {expected}\n")
    assert hub.downloads("model.bin") == 0
    assert list(tmp_path.iterdir()) == [tmp_path / "hf"]


def test_a_model_bin_that_is_not_whisper_is_named_and_leaves_no_directory(
    hub: FakeHub, tmp_path: Path, faster_whisper: FasterWhisper
) -> None:
    # another CTranslate2 model's model.bin beside a Whisper config.json: only its header tells
    hub.repositories["someone/faster-whisper"] = {
        **faster_whisper.files,
        "model.bin": model_bin_bytes([], spec="TransformerSpec", revision=7),
    }
    done = pull(hub, tmp_path, "someone/faster-whisper", str(tmp_path / "model"))
    snapshot = tmp_path / "hf" / "hub" / "models--someone--faster-whisper" / "snapshots"
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr.endswith(
        "error: someone/faster-whisper: the files downloaded are not a model the engine loads: "
        f"{snapshot / hub.commit('someone/faster-whisper')}/model.bin: a CTranslate2 TransformerSpec model, "
        "not Whisper (WhisperSpec)\n"
    )
    assert list(tmp_path.iterdir()) == [tmp_path / "hf"]


def test_an_unknown_name_lists_the_known_ones(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["parakeet-large", str(tmp_path / "model")]) == 2
    assert capsys.readouterr().err == (
        "error: unknown model 'parakeet-large': give OWNER/REPO (a model repository on the Hugging Face Hub) "
        "or one of faster-whisper-base, faster-whisper-base.en, faster-whisper-large-v1, faster-whisper-large-v2, "
        "faster-whisper-large-v3, faster-whisper-medium, faster-whisper-medium.en, faster-whisper-small, "
        "faster-whisper-small.en, faster-whisper-tiny, faster-whisper-tiny.en, nemo-parakeet-ctc-0.6b, "
        "nemo-parakeet-rnnt-0.6b, nemo-parakeet-tdt-0.6b-v2, nemo-parakeet-tdt-0.6b-v3, whisper-base, "
        "whisper-large-v3-turbo, whisper-small, whisper-tiny\n"
    )
    assert not (tmp_path / "model").exists()


def test_without_huggingface_hub_one_line_says_what_to_install(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "huggingface_hub", None)  # import fails, as when not installed
    assert main([TDT_NAME, str(tmp_path / "model")]) == 2
    assert capsys.readouterr().err == (
        "error: speech-event pull needs huggingface_hub: pip install 'speech-event[pull]'\n"
    )


def test_an_existing_directory_is_never_written_over(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    directory = tmp_path / "in-use"
    directory.mkdir()
    (directory / "config.json").write_text("{}")
    assert main([TDT_NAME, str(directory)]) == 2
    assert capsys.readouterr().err == (
        f"error: {directory} already exists: pull writes a new directory, never over one that may be in use "
        "(remove it, or give another)\n"
    )
    assert _listing(directory) == {"config.json": b"{}"}


@pytest.mark.parametrize(
    ("files", "message"),
    [
        (
            {"encoder.onnx": b"", "decoder.onnx": b"", "joiner.onnx": b"", "tokens.txt": b""},
            "someone/other holds no model directory speech-event runs: it has decoder.onnx, encoder.onnx, joiner.onnx, "
            "tokens.txt; it needs encoder-model.onnx and decoder_joint-model.onnx for a NeMo transducer (RNN-T "
            "or TDT), model.onnx for a NeMo CTC model, encoder_model.onnx and decoder_model_merged.onnx for a "
            "Whisper model (Hugging Face optimum's export), or model.bin for a faster-whisper (CTranslate2) "
            "Whisper model",
        ),
        (
            {"whisper-base_beamsearch.onnx": b"", "config.json": b'{"model_type": "whisper-ort"}'},
            "someone/other: its config.json's model_type is 'whisper-ort', which speech-event does not run; it runs "
            "nemo-conformer-rnnt, nemo-conformer-tdt, nemo-conformer-ctc and whisper",
        ),
    ],
    ids=["sherpa-onnx", "onnx-asr-whisper-ort"],
)
def test_a_repository_of_another_layout_says_what_it_lacks(
    hub: FakeHub, tmp_path: Path, files: Dict[str, bytes], message: str
) -> None:
    hub.repositories["someone/other"] = files
    done = pull(hub, tmp_path, "someone/other", str(tmp_path / "model"))
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == f"error: {message}\n"
    assert not (tmp_path / "model").exists()
    assert [name for name in files if name != "config.json" and hub.downloads(name)] == []


@pytest.mark.parametrize(
    ("removed", "arguments", "message"),
    [
        (
            ["vocab.txt"],
            [],
            "is a NeMo transducer (RNN-T or TDT) but has no vocab.txt: the engine needs encoder-model.onnx, "
            "decoder_joint-model.onnx and vocab.txt",
        ),
        (
            ["encoder-model.int8.onnx", "decoder_joint-model.int8.onnx"],
            ["--int8"],
            "is a NeMo transducer (RNN-T or TDT) but has no encoder-model.int8.onnx and "
            "decoder_joint-model.int8.onnx (it has the fp32 files: pull without --int8): the engine needs "
            "encoder-model.int8.onnx, decoder_joint-model.int8.onnx and vocab.txt",
        ),
    ],
    ids=["vocabulary", "int8"],
)
def test_a_missing_file_is_named_before_anything_large_is_downloaded(
    hub: FakeHub,
    tmp_path: Path,
    tdt_files: Dict[str, bytes],
    removed: List[str],
    arguments: List[str],
    message: str,
) -> None:
    hub.repositories["someone/partial"] = {
        name: data for name, data in tdt_files.items() if name not in removed
    }
    done = pull(hub, tmp_path, "someone/partial", str(tmp_path / "model"), *arguments)
    assert (done.returncode, done.stdout, done.stderr) == (2, "", f"error: someone/partial {message}\n")
    assert not (tmp_path / "model").exists()
    assert [name for name in tdt_files if name.endswith((".onnx", ".data")) and hub.downloads(name)] == []


def test_a_repository_the_hub_does_not_have_is_named(hub: FakeHub, tmp_path: Path) -> None:
    done = pull(hub, tmp_path, "someone/absent", str(tmp_path / "model"))
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == (
        f"error: someone/absent: no such model repository on {hub.url} (a private or gated one needs HF_TOKEN)\n"
    )


def test_a_hub_that_cannot_be_reached_fails_with_status_1_to_run_again(hub: FakeHub, tmp_path: Path) -> None:
    hub.shutdown()
    hub.server_close()  # nothing listens on its port any more
    done = pull(hub, tmp_path, TDT_NAME, str(tmp_path / "model"))
    assert (done.returncode, done.stdout) == (1, "")
    assert done.stderr.startswith(f"error: downloading {TDT_REPOSITORY} from {hub.url} failed (")
    assert done.stderr.endswith("); run the same command again to resume\n")
    assert not (tmp_path / "model").exists()


def test_a_connection_dropped_mid_file_is_fetched_again_and_the_directory_is_whole(
    hub: FakeHub, tmp_path: Path, tdt_files: Dict[str, bytes]
) -> None:
    hub.repositories[TDT_REPOSITORY] = tdt_files
    hub.drop = "encoder-model.onnx.data"
    directory = tmp_path / "model"
    done = pull(hub, tmp_path, TDT_NAME, str(directory))
    assert done.returncode == 0, done.stderr
    # huggingface_hub tries again (from where it stopped, or from the start: as its version does)
    assert hub.downloads("encoder-model.onnx.data") == 2
    assert _listing(directory)["encoder-model.onnx.data"] == tdt_files["encoder-model.onnx.data"]


def test_a_pull_cut_off_halfway_leaves_no_directory_and_a_rerun_completes_it(
    hub: FakeHub, tmp_path: Path, tdt_files: Dict[str, bytes]
) -> None:
    hub.repositories[TDT_REPOSITORY] = tdt_files
    hub.hold = "encoder-model.onnx.data"
    directory = tmp_path / "model"
    command = [
        sys.executable,
        "-c",
        "import sys; from speech_event.application import main; sys.exit(main())",
    ]
    cut = subprocess.Popen(
        [*command, "pull", TDT_NAME, str(directory)],
        env=_environment(hub, tmp_path),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        assert hub.halfway.wait(SECONDS)
        assert not directory.exists()
    finally:
        cut.kill()  # as a power cut or a kill -9 would
        cut.wait(SECONDS)
    assert not directory.exists()
    assert [path.name for path in tmp_path.iterdir() if path.name.startswith(".model")] == []
    hub.hold = None
    hub.release.set()
    done = pull(hub, tmp_path, TDT_NAME, str(directory))
    assert done.returncode == 0, done.stderr
    assert done.stdout == f"model parakeet\nen_model_path {directory}\n"
    assert _listing(directory)["encoder-model.onnx.data"] == tdt_files["encoder-model.onnx.data"]
    assert hub.downloads("config.json") == 1  # what the cut-off run had finished is not fetched again


def test_pull_is_dispatched_by_the_speech_event_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from speech_event.application import main as speech_event

    assert speech_event(["pull", "no-such-model", str(tmp_path / "model")]) == 2
    assert capsys.readouterr().err.startswith("error: unknown model 'no-such-model'")
