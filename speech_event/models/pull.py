"""``speech-event pull NAME|OWNER/REPO DIR [--int8]``: a published model directory from the Hugging
Face Hub, checked and ready for the node, with the configuration lines that use it.

Needs huggingface_hub (the ``pull`` extra) and honours its settings: ``HF_ENDPOINT`` (a mirror),
``HF_HOME`` or ``HF_HUB_CACHE`` (where downloads are kept), ``HF_TOKEN``, its progress bars.

1. NAME is one of KNOWN (the Parakeet exports as onnx-asr names them, the Whisper sizes, Systran's
   faster-whisper models) or any OWNER/REPO.
2. The repository's file list (and its config.json's ``model_type``) says its layout: a NeMo
   transducer (``encoder-model.onnx``, ``decoder_joint-model.onnx``), a NeMo CTC model
   (``model.onnx``), both with ``vocab.txt``, a Whisper model as Hugging Face optimum exports it
   (``encoder_model.onnx``, ``decoder_model_merged.onnx``, ``vocab.json``, ``added_tokens.json``),
   or a faster-whisper (CTranslate2) model (``model.bin``, ``config.json`` and a vocabulary:
   ``vocabulary.json``, ``vocabulary.txt`` or ``tokenizer.json``; CTranslate2's vocabulary files
   alone tell it too). ``--int8`` takes the int8 files instead (``encoder-model.int8.onnx``,
   ``encoder_model_int8.onnx``; a faster-whisper model's conversion is quantized). A repository
   of another layout, or without a file the engine needs, is named before anything large is
   downloaded; for faster-whisper, so is one whose config.json is not CTranslate2's Whisper
   config, or that cannot be converted here (conversion.py).
3. Only those files (with their ``*.onnx.data``, and config.json and tokenizer files when there) are
   downloaded, into huggingface_hub's cache: a rerun after a cut-off download downloads again only
   what it had not finished.
4. They are linked (copied across file systems) into a temporary sibling of DIR, or for
   faster-whisper converted into it (conversion.py), checked there (every file, the family, for
   NeMo the manifest the engine reads), and the sibling is renamed to DIR: DIR never exists
   half-written, and an existing DIR is never touched.
5. stdout gets the configuration lines that use it, ``model FAMILY`` and ``en_model_path DIR``
   (``rw_model_path`` with ``--language kinyarwanda``), so ``> models.ini`` is a configuration file.

Exit status 0; 1 when the download failed (run it again: it resumes); 2 for what a rerun would not change.
"""

import argparse
import fnmatch
import json
import os
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

from speech_event.errors import ModelError
from speech_event.exporters.faster_whisper import CONFIG_FILE, MODEL_FILE, VOCABULARY_FILES
from speech_event.models.conversion import check_convertible, convert
from speech_event.recognizers.nemo.manifest import CTC, RNNT, TDT, load_manifest
from speech_event.recognizers.nemo.vocabulary import load_vocabulary
from speech_event.recognizers.onnx.directory import MANIFEST_FILE
from speech_event.recognizers.onnx.families import family_of
from speech_event.recognizers.whisper.manifest import WHISPER
from speech_event.recognizers.whisper.optimum_layout import load_optimum_manifest, load_optimum_pieces

# faster-whisper's own model names, as Systran publishes them (CTranslate2's layout, converted)
FASTER_WHISPER_SIZES = (
    "tiny.en",
    "tiny",
    "base.en",
    "base",
    "small.en",
    "small",
    "medium.en",
    "medium",
    "large-v1",
    "large-v2",
    "large-v3",
)
# Known names -> Hugging Face repositories: onnx-asr's names of the NeMo exports, the Whisper sizes
# onnx-asr loads from onnx-community (optimum's layout; onnx-asr's own "whisper-base" is
# istupakov/whisper-base-onnx, an onnxruntime beam-search export the Whisper engine does not read),
# and Systran's faster-whisper repositories.
KNOWN: Dict[str, str] = {
    "nemo-parakeet-tdt-0.6b-v2": "istupakov/parakeet-tdt-0.6b-v2-onnx",
    "nemo-parakeet-tdt-0.6b-v3": "istupakov/parakeet-tdt-0.6b-v3-onnx",
    "nemo-parakeet-ctc-0.6b": "istupakov/parakeet-ctc-0.6b-onnx",
    "nemo-parakeet-rnnt-0.6b": "istupakov/parakeet-rnnt-0.6b-onnx",
    "whisper-tiny": "onnx-community/whisper-tiny",
    "whisper-base": "onnx-community/whisper-base",
    "whisper-small": "onnx-community/whisper-small",
    "whisper-large-v3-turbo": "onnx-community/whisper-large-v3-turbo",
    **{f"faster-whisper-{size}": f"Systran/faster-whisper-{size}" for size in FASTER_WHISPER_SIZES},
}
INSTALL = "speech-event pull needs huggingface_hub: pip install 'speech-event[pull]'"
DOWNLOAD_FAILED, UNUSABLE = 1, 2
LANGUAGE_KEYS = {"english": "en_model_path", "kinyarwanda": "rw_model_path"}
# Listed at most, of a repository's files, in a message
SHOWN_FILES = 12


@dataclass(frozen=True)
class Layout:
    """A model directory layout an engine reads, or that is converted into one: its model files
    (fp32 and int8, as published) and the other files it needs or takes when there. A name
    starting ``**/`` may be in any folder of the repository (optimum puts its ONNX files in
    ``onnx/``); the others are at its root."""

    description: str
    models: Tuple[str, ...]
    int8_models: Tuple[str, ...]  # fnmatch patterns: onnx-community writes _int8, istupakov .int8
    needed: Tuple[str, ...]
    optional: Tuple[str, ...]
    model_types: Tuple[str, ...]  # config.json's model_type of this layout
    one_of: Tuple[str, ...] = ()  # files of which it needs one: the first there is taken
    signs: Tuple[str, ...] = ()  # files that tell the layout without its model files, to name those

    def names(self, int8: bool) -> List[str]:
        """The files the engine needs (one_of apart), as said in messages."""
        return [_shown(name) for name in (self.int8_models if int8 else self.models) + self.needed]

    def needs(self, int8: bool) -> str:
        """Every file the engine needs, as said in messages."""
        return _joined(self.names(int8) + ([f"one of {_either(self.one_of)}"] if self.one_of else []))


NEMO_TRANSDUCER = Layout(
    "a NeMo transducer (RNN-T or TDT)",
    ("encoder-model.onnx", "decoder_joint-model.onnx"),
    ("encoder-model.int8.onnx", "decoder_joint-model.int8.onnx"),
    ("vocab.txt",),
    (MANIFEST_FILE,),
    (RNNT, TDT),
)
NEMO_CTC = Layout(
    "a NeMo CTC model", ("model.onnx",), ("model.int8.onnx",), ("vocab.txt",), (MANIFEST_FILE,), (CTC,)
)
WHISPER_OPTIMUM = Layout(
    "a Whisper model (Hugging Face optimum's export)",
    ("**/encoder_model.onnx", "**/decoder_model_merged.onnx"),
    ("**/encoder_model?int8.onnx", "**/decoder_model_merged?int8.onnx"),
    ("vocab.json", "added_tokens.json"),
    (
        MANIFEST_FILE,
        "generation_config.json",
        "preprocessor_config.json",
        "tokenizer.json",
        "tokenizer_config.json",
        "merges.txt",
        "special_tokens_map.json",
        "normalizer.json",
    ),
    ("whisper",),
)
# CTranslate2's Whisper, converted after download; int8 is a quantization of the conversion, so the
# same files either way. Its config.json has no model_type: its files tell it.
FASTER_WHISPER = Layout(
    "a faster-whisper (CTranslate2) Whisper model",
    (MODEL_FILE,),
    (MODEL_FILE,),
    (CONFIG_FILE,),
    (),
    (),
    one_of=VOCABULARY_FILES,
    signs=tuple(name for name in VOCABULARY_FILES if name.startswith("vocabulary.")),
)
LAYOUTS = (NEMO_TRANSDUCER, NEMO_CTC, WHISPER_OPTIMUM, FASTER_WHISPER)


class PullError(Exception):
    """What stops a pull, and its exit status (1: a rerun may succeed; 2: it would not)."""

    def __init__(self, message: str, status: int = UNUSABLE) -> None:
        super().__init__(message)
        self.status = status


def _shown(pattern: str) -> str:
    """A file pattern as a user reads it: the fp32-like name."""
    return pattern.replace("**/", "").replace("?int8", "_int8")


def _joined(words: Sequence[str], last: str = "and") -> str:
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} {last} {words[-1]}"


def _either(words: Sequence[str]) -> str:
    return _joined(words, "or")


def repository_of(name: str) -> str:
    """The Hub repository of a known name or an OWNER/REPO; PullError lists the known names."""
    if name in KNOWN:
        return KNOWN[name]
    owner, slash, repository = name.partition("/")
    if slash and owner and repository and "/" not in repository:
        return name
    raise PullError(
        f"unknown model {name!r}: give OWNER/REPO (a model repository on the Hugging Face Hub) or one of "
        f"{', '.join(sorted(KNOWN))}"
    )


def find(files: Sequence[str], pattern: str) -> Optional[str]:
    """The repository file ``pattern`` names: at the root, or for ``**/`` in any folder (the
    shallowest, then the first by name)."""
    anywhere = pattern.startswith("**/")
    base = pattern[3:] if anywhere else pattern
    found = sorted(
        (path.count("/"), path)
        for path in files
        if fnmatch.fnmatchcase(path.rsplit("/", 1)[-1], base) and (anywhere or "/" not in path)
    )
    return found[0][1] if found else None


def layout_of(repository: str, files: Sequence[str], model_type: Optional[str]) -> Layout:
    """The layout config.json's ``model_type`` names, else the first whose ONNX files are there."""
    if model_type is not None:
        for layout in LAYOUTS:
            if model_type in layout.model_types:
                return layout
        runs = [known for layout in LAYOUTS for known in layout.model_types]
        raise PullError(
            f"{repository}: its config.json's model_type is {model_type!r}, which speech-event does not "
            f"run; it runs {_joined(runs)}"
        )
    for layout in LAYOUTS:
        if any(find(files, pattern) for pattern in layout.models + layout.int8_models + layout.signs):
            return layout
    expected = [
        f"{_joined([_shown(name) for name in layout.models])} for {layout.description}" for layout in LAYOUTS
    ]
    listed = ", ".join(files[:SHOWN_FILES]) + (
        f" and {len(files) - SHOWN_FILES} more" if len(files) > SHOWN_FILES else ""
    )
    raise PullError(
        f"{repository} holds no model directory speech-event runs: it has {listed or 'no files'}; "
        f"it needs {', '.join(expected[:-1])}, or {expected[-1]}"
    )


def needed_files(repository: str, files: Sequence[str], layout: Layout, int8: bool) -> List[str]:
    """The repository's files to download for ``layout`` (fp32 or int8): the ONNX files and their
    external data, the needed files, the optional ones that are there. PullError names the missing."""
    models = layout.int8_models if int8 else layout.models
    missing = [_shown(name) for name in models + layout.needed if find(files, name) is None]
    one = next((path for path in (find(files, name) for name in layout.one_of) if path), None)
    lacks = ([f"no {_joined(missing)}"] if missing else []) + (
        [f"none of {_either(layout.one_of)}"] if layout.one_of and one is None else []
    )
    if lacks:
        other = layout.models if int8 else layout.int8_models
        if missing and other != models and all(find(files, name) for name in other + layout.needed):
            hint = (
                " (it has the fp32 files: pull without --int8)"
                if int8
                else " (it has the int8 files: add --int8)"
            )
        else:
            hint = ""
        raise PullError(
            f"{repository} is {layout.description} but has {' and '.join(lacks)}{hint}: the engine needs "
            f"{layout.needs(int8)}"
        )
    chosen = [path for path in (find(files, name) for name in models + layout.needed) if path]
    chosen += [one] if one else []
    data = [
        path
        for path in files
        for model in chosen[: len(models)]
        if fnmatch.fnmatchcase(path, model + "?data")
    ]
    optional = [path for path in (find(files, name) for name in layout.optional) if path]
    return chosen + data + [path for path in optional if path not in chosen]


def _hub() -> Any:
    """huggingface_hub, or PullError saying what to install."""
    try:
        import huggingface_hub
        import huggingface_hub.constants
        import huggingface_hub.utils
    except ImportError:
        raise PullError(INSTALL) from None
    return huggingface_hub


def _download_error(hub: Any, repository: str, problem: Exception) -> PullError:
    endpoint = hub.constants.ENDPOINT
    if isinstance(problem, hub.utils.RepositoryNotFoundError):
        return PullError(
            f"{repository}: no such model repository on {endpoint} (a private or gated one needs HF_TOKEN)"
        )
    if isinstance(problem, ValueError):  # huggingface_hub's HFValidationError: not a repository name
        return PullError(f"{repository}: {problem}")
    return PullError(
        f"downloading {repository} from {endpoint} failed ({type(problem).__name__}: {problem}); "
        "run the same command again to resume",
        DOWNLOAD_FAILED,
    )


def _fetch(hub: Any, repository: str, int8: bool, language: str) -> Tuple[Layout, Path, List[str]]:
    """The layout, the snapshot folder in huggingface_hub's cache, and the files downloaded into it."""
    try:
        info = hub.HfApi().model_info(repository)
        revision = info.sha
        files = [sibling.rfilename for sibling in info.siblings or ()]
        config = (
            hub.hf_hub_download(repository, MANIFEST_FILE, revision=revision)
            if MANIFEST_FILE in files
            else None
        )
    except Exception as problem:  # huggingface_hub's and its HTTP client's, whichever its version
        raise _download_error(hub, repository, problem) from None
    layout = layout_of(repository, files, None if config is None else _model_type(repository, Path(config)))
    wanted = needed_files(repository, files, layout, int8)
    if layout is FASTER_WHISPER and config is not None:  # needed_files made sure it is there
        try:
            check_convertible(Path(config), language)
        except ModelError as problem:
            raise PullError(f"{repository}: {problem}") from None
    print(f"{repository}: {layout.description}; downloading {_joined(wanted)}", file=sys.stderr)
    try:
        snapshot = hub.snapshot_download(repository, revision=revision, allow_patterns=wanted)
    except Exception as problem:
        raise _download_error(hub, repository, problem) from None
    return layout, Path(snapshot), wanted


def _model_type(repository: str, config: Path) -> Optional[str]:
    """config.json's model_type; None when it names none."""
    try:
        document = json.loads(config.read_text(encoding="utf-8"))
    except ValueError as problem:
        raise PullError(f"{repository}: its {MANIFEST_FILE} is not JSON ({problem})") from None
    if isinstance(document, dict) and "model_type" in document:
        return str(document["model_type"])
    return None


def _placed(snapshot: Path, files: Sequence[str], partial: Path) -> None:
    """``files`` of the snapshot, each by its own name, in ``partial``: hard links to the cache's
    blobs where the file system allows, else copies."""
    partial.mkdir()
    for name in files:
        source, target = os.path.realpath(snapshot / name), partial / name.rsplit("/", 1)[-1]
        try:
            os.link(source, target)
        except OSError:
            shutil.copyfile(source, target)


def _family(directory: Path, layout: Layout, int8: bool) -> str:
    """The family of the model in ``directory`` as the engine reads it; ModelError when it would not load."""
    for name in layout.names(int8):
        if not any(directory.glob(name.replace("_int8", "?int8"))):
            raise ModelError(f"{directory}: missing {name}")
    if layout is WHISPER_OPTIMUM:
        manifest = load_optimum_manifest(directory)
        load_optimum_pieces(directory, manifest.vocabulary_size)
        return family_of(directory, unrecorded=WHISPER)
    load_vocabulary(directory / "vocab.txt")
    return load_manifest(directory / MANIFEST_FILE).family


def pull(name: str, directory: Path, int8: bool, language: str) -> Tuple[str, Path]:
    """Fetch ``name`` into ``directory`` for ``language``; its family and absolute path. PullError says
    what went wrong."""
    repository = repository_of(name)
    directory = directory.absolute()
    if directory.exists() and (not directory.is_dir() or any(directory.iterdir())):
        raise PullError(
            f"{directory} already exists: pull writes a new directory, never over one that may be in use "
            "(remove it, or give another)"
        )
    hub = _hub()
    layout, snapshot, files = _fetch(hub, repository, int8, language)
    partial = directory.parent / f".{directory.name}.partial"
    shutil.rmtree(partial, ignore_errors=True)  # what a pull cut off while placing or converting left
    directory.parent.mkdir(parents=True, exist_ok=True)
    try:
        if layout is FASTER_WHISPER:
            print(
                f"{repository}: converting to the Whisper engine's ONNX files"
                + (" and quantizing them to int8" if int8 else ""),
                file=sys.stderr,
            )
            family = convert(snapshot, partial, int8)
        else:
            _placed(snapshot, files, partial)
            family = _family(partial, layout, int8)
        if directory.exists():
            directory.rmdir()  # empty, as checked above
        os.rename(partial, directory)
    except ModelError as problem:
        raise PullError(
            f"{repository}: the files downloaded are not a model the engine loads: {problem}"
        ) from None
    finally:
        shutil.rmtree(partial, ignore_errors=True)
    return family, directory


def main(argv: List[str]) -> int:
    """The ``speech-event pull`` command; returns its exit status."""
    parser = argparse.ArgumentParser(
        prog="speech-event pull",
        description="Fetch a published model directory from the Hugging Face Hub (HF_ENDPOINT, HF_HOME), "
        "check it, and print the configuration lines that use it.",
        epilog="known names:\n"
        + "\n".join(f"  {name:26} {repository}" for name, repository in KNOWN.items()),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "name", help="a known name, or OWNER/REPO of a model repository on the Hugging Face Hub"
    )
    parser.add_argument("directory", type=Path, help="the model directory to write (must not exist yet)")
    parser.add_argument(
        "--int8", action="store_true", help="the int8 files (faster on a CPU) instead of fp32"
    )
    parser.add_argument(
        "--language",
        choices=sorted(LANGUAGE_KEYS),
        default="english",
        help="the language it serves: en_model_path or rw_model_path in the lines printed (default english)",
    )
    arguments = parser.parse_args(argv)
    try:
        family, directory = pull(arguments.name, arguments.directory, arguments.int8, arguments.language)
    except PullError as problem:
        print(f"error: {problem}", file=sys.stderr)
        return problem.status
    print(f"{directory}: a {family} model; its configuration lines:", file=sys.stderr)
    print(f"model {family}")
    print(f"{LANGUAGE_KEYS[arguments.language]} {directory}")
    return 0
