"""``speech-event export-whisper MODEL OUT_DIR``: a Whisper model to the directory the Whisper engine
loads. MODEL is a faster-whisper (CTranslate2) directory, converted with numpy and onnx alone
(faster_whisper.py), or an openai-whisper checkpoint (a name such as ``base`` from whisper's cache,
or a .pt file), exported with torch.

Writes encoder.onnx (the mel window to each decoder block's cross-attention keys and values),
decoder.onnx (tokens and the self-attention cache of the tokens before -> logits and the grown
cache, so decoding costs one position a step), tokens.txt (every token's bytes, from whisper's
tiktoken tokenizer) and config.json (the special tokens, the languages, and the tokens Whisper's
rules suppress, from whisper's own tokenizer). ``--language kinyarwanda=CODE`` names the language
token a checkpoint was fine-tuned to use for Kinyarwanda, which Whisper has none for.
A checkpoint needs torch and openai-whisper (the ``export`` extra) on a workstation; never on the robot.
"""

import argparse
import sys
from pathlib import Path
from typing import Any, Dict, List, Tuple

from speech_event.errors import ModelError
from speech_event.exporters.faster_whisper import export_faster_whisper, is_faster_whisper_directory
from speech_event.exporters.quantize import INT8_HELP, quantize_and_say
from speech_event.exporters.whisper_directory import languages_of, write_text_files
from speech_event.recognizers.whisper.manifest import WhisperManifest
from speech_event.recognizers.whisper.model import DECODER_FILE, ENCODER_FILE, cross_names

OPSET = 17


def parse_language(setting: str) -> Tuple[str, str]:
    """A ``--language LANGUAGE=CODE`` argument as (language, Whisper's language code)."""
    language, _, code = setting.partition("=")
    if not language or not code:
        raise argparse.ArgumentTypeError(f"{setting!r}: write LANGUAGE=CODE, e.g. kinyarwanda=sw")
    return language, code


def _wrappers(model: Any) -> Tuple[Any, Any]:
    """The encoder and decoder as whisper computes them (its qkv_attention: q and k each scaled by
    head_width ** -0.25, softmax in float32), with the attention's heads split once: each block's
    cross keys come out split, scaled and transposed, a tensor a block, so a decoding step moves
    no audio-sized tensor."""
    import torch
    import torch.nn.functional as F

    def heads_of(x: Any, heads: int) -> Any:
        """[1, positions, width] -> [1, heads, positions, head width]."""
        return x.view(x.shape[0], x.shape[1], heads, -1).permute(0, 2, 1, 3)

    def attend(q: Any, k_transposed: Any, v: Any, mask: Any) -> Any:
        scores = q @ k_transposed
        if mask is not None:
            scores = scores + mask
        weights = F.softmax(scores.float(), dim=-1).to(q.dtype)
        return (weights @ v).permute(0, 2, 1, 3).flatten(start_dim=2)

    class Encoder(torch.nn.Module):  # type: ignore[misc]  # torch is untyped here
        def __init__(self) -> None:
            super().__init__()
            self.encoder, self.blocks = model.encoder, model.decoder.blocks

        def forward(self, mel: Any) -> Tuple[Any, ...]:
            audio = self.encoder(mel)
            cross = []
            for block in self.blocks:
                heads = block.cross_attn.n_head
                scale = (audio.shape[-1] // heads) ** -0.25
                cross.append(heads_of(block.cross_attn.key(audio), heads).transpose(-1, -2) * scale)
                cross.append(heads_of(block.cross_attn.value(audio), heads))
            return tuple(cross)

    class Decoder(torch.nn.Module):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__()
            self.decoder = model.decoder

        def forward(self, tokens: Any, self_k: Any, self_v: Any, *cross: Any) -> Tuple[Any, Any, Any]:
            decoder = self.decoder
            past = self_k.shape[3]
            positions = torch.arange(tokens.shape[1]) + past
            x = decoder.token_embedding(tokens) + decoder.positional_embedding[positions]
            keys = torch.arange(past + tokens.shape[1])
            mask = torch.where(keys[None, :] > positions[:, None], float("-inf"), 0.0)
            new_k, new_v = [], []
            for index, block in enumerate(decoder.blocks):
                heads = block.attn.n_head
                scale = (x.shape[-1] // heads) ** -0.25
                h = block.attn_ln(x)
                k = torch.cat([self_k[index], heads_of(block.attn.key(h), heads)], dim=2)
                v = torch.cat([self_v[index], heads_of(block.attn.value(h), heads)], dim=2)
                new_k.append(k)
                new_v.append(v)
                q = heads_of(block.attn.query(h), heads) * scale
                x = x + block.attn.out(attend(q, (k * scale).transpose(-1, -2), v, mask))
                h = block.cross_attn_ln(x)
                q = heads_of(block.cross_attn.query(h), heads) * scale
                x = x + block.cross_attn.out(attend(q, cross[2 * index], cross[2 * index + 1], None))
                x = x + block.mlp(block.mlp_ln(x))
            x = decoder.ln(x)
            logits = (x @ decoder.token_embedding.weight.to(x.dtype).T).float()
            return logits, torch.stack(new_k), torch.stack(new_v)

    return Encoder().eval(), Decoder().eval()


def export_model(model: Any, out_dir: Path) -> None:
    """The encoder and decoder of a loaded whisper model as ONNX files."""
    import torch

    dims = model.dims
    encoder, decoder = _wrappers(model)
    mel = torch.zeros(1, dims.n_mels, 2 * dims.n_audio_ctx)
    with torch.no_grad():
        cross = encoder(mel)
        names = cross_names(dims.n_text_layer)
        torch.onnx.export(
            encoder,
            (mel,),
            str(out_dir / ENCODER_FILE),
            input_names=["mel"],
            output_names=names,
            opset_version=OPSET,
            dynamo=False,
        )
        head_width = dims.n_text_state // dims.n_text_head
        cache = torch.zeros(dims.n_text_layer, 1, dims.n_text_head, 2, head_width)
        tokens = torch.zeros(1, 3, dtype=torch.long)
        torch.onnx.export(
            decoder,
            (tokens, cache, cache, *cross),
            str(out_dir / DECODER_FILE),
            input_names=["tokens", "self_k", "self_v", *names],
            output_names=["logits", "new_self_k", "new_self_v"],
            dynamic_axes={
                "tokens": {1: "tokens"},
                "self_k": {3: "past"},
                "self_v": {3: "past"},
                "logits": {1: "tokens"},
                "new_self_k": {3: "positions"},
                "new_self_v": {3: "positions"},
            },
            opset_version=OPSET,
            dynamo=False,
        )
    # torch.onnx folds the transposed embedding the logits read into a second copy of it
    import onnx

    from speech_event.exporters.whisper_graphs import share_transposed_embedding

    decoder_path = out_dir / DECODER_FILE
    exported = onnx.load(str(decoder_path))
    if share_transposed_embedding(exported):
        onnx.save(exported, str(decoder_path))


def manifest_of(model: Any, tokenizer: Any, named: Dict[str, str]) -> WhisperManifest:
    """What the engine needs of whisper's tokenizer and decoding rules (whisper.decoding's
    _get_suppress_tokens with suppress_tokens "-1", and SuppressBlank)."""
    suppress = set(tokenizer.non_speech_tokens)
    suppress |= {
        tokenizer.transcribe,
        tokenizer.translate,
        tokenizer.sot,
        tokenizer.sot_prev,
        tokenizer.sot_lm,
    }
    if tokenizer.no_speech is not None:
        suppress.add(tokenizer.no_speech)
    return WhisperManifest(
        mel_bands=model.dims.n_mels,
        vocabulary_size=model.dims.n_vocab,
        text_context=model.dims.n_text_ctx,
        sot=tokenizer.sot,
        eot=tokenizer.eot,
        no_timestamps=tokenizer.no_timestamps,
        timestamp_begin=tokenizer.timestamp_begin,
        languages=languages_of(model.is_multilingual, named, tokenizer.to_language_token),
        suppress=tuple(sorted(suppress)),
        suppress_at_start=(*tokenizer.encode(" "), tokenizer.eot),
        transcribe=tokenizer.transcribe if model.is_multilingual else None,
        no_speech=tokenizer.no_speech,
    )


def token_bytes(tokenizer: Any, count: int) -> List[bytes]:
    """The bytes of token ids 0 to ``count`` - 1; empty for an id the tokenizer does not have."""
    pieces = []
    for token in range(count):
        try:
            pieces.append(tokenizer.encoding.decode_single_token_bytes(token))
        except KeyError:  # an id the checkpoint has but the tokenizer does not: it never reads as text
            pieces.append(b"")
    return pieces


def export(model_path: str, out_dir: Path, named: Dict[str, str]) -> WhisperManifest:
    """Export a faster-whisper directory or a whisper checkpoint to ``out_dir``: the ONNX files,
    tokens.txt and config.json."""
    if is_faster_whisper_directory(Path(model_path)):
        return export_faster_whisper(Path(model_path), out_dir, named)
    return export_checkpoint(model_path, out_dir, named)


def export_checkpoint(checkpoint: str, out_dir: Path, named: Dict[str, str]) -> WhisperManifest:
    """Export a whisper checkpoint to ``out_dir`` (torch and openai-whisper)."""
    try:
        import whisper
        from whisper.tokenizer import get_tokenizer
    except ImportError:
        raise ModelError(
            f"{checkpoint} is not a faster-whisper directory (a directory with model.bin), so "
            "export-whisper reads it as an openai-whisper checkpoint, which needs openai-whisper: "
            "pip install 'speech-event[export]' (openai-whisper and torch); only for exporting, never on "
            "the robot"
        ) from None
    model = whisper.load_model(checkpoint, device="cpu")
    model.eval()
    tokenizer = get_tokenizer(model.is_multilingual, num_languages=model.num_languages, task="transcribe")
    try:
        manifest = manifest_of(model, tokenizer, named)
    except KeyError as problem:
        raise ModelError(f"{checkpoint}: whisper's tokenizer has no language {problem}") from None
    out_dir.mkdir(parents=True, exist_ok=True)
    export_model(model, out_dir)
    write_text_files(out_dir, token_bytes(tokenizer, model.dims.n_vocab), manifest)
    return manifest


def main(argv: List[str]) -> int:
    """The ``speech-event export-whisper`` command; returns its exit status."""
    parser = argparse.ArgumentParser(prog="speech-event export-whisper", description=__doc__)
    parser.add_argument(
        "model",
        help="a faster-whisper (CTranslate2) model directory, or an openai-whisper model name (tiny, "
        "base, ...) or checkpoint file (.pt)",
    )
    parser.add_argument("out_dir", type=Path, help="the model directory to write")
    parser.add_argument(
        "--language",
        type=parse_language,
        action="append",
        default=[],
        metavar="LANGUAGE=CODE",
        help="the Whisper language code whose token the checkpoint uses for LANGUAGE (e.g. kinyarwanda=sw)",
    )
    parser.add_argument("--int8", action="store_true", help=INT8_HELP)
    arguments = parser.parse_args(argv)
    try:
        manifest = export(arguments.model, arguments.out_dir, dict(arguments.language))
    except ModelError as problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    languages = ", ".join(sorted(manifest.languages))
    print(
        f"wrote {arguments.out_dir} (whisper; languages {languages}): set model whisper and the model paths"
    )
    if arguments.int8:
        quantize_and_say(arguments.out_dir)
    return 0
