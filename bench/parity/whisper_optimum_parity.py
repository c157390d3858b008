"""Parity of the Whisper engine on Hugging Face optimum's layout with openai-whisper itself (a tool,
not CI): needs torch, openai-whisper, transformers and optimum-onnx, in a throwaway venv.

    python3 -m venv /tmp/optenv
    /tmp/optenv/bin/pip install torch==2.13.0 transformers optimum-onnx onnxruntime openai-whisper
    PYTHONPATH=. /tmp/optenv/bin/python -m bench.parity.whisper_optimum_parity [tiny base]

For each shape: bench/parity/whisper_parity.py's random checkpoint (whisper's ModelDimensions, the
multilingual vocabulary, sentences that end), converted to transformers' WhisperForConditionalGeneration
(the weights renamed as transformers' convert_openai_to_hf does), with the tokenizer files
transformers writes for a tokenizer built from whisper's own tiktoken file and special tokens, and
the generation config of Hugging Face's Whisper repositories (suppress_tokens, begin_suppress_tokens,
lang_to_id, task_to_id) from whisper's tokenizer; exported by optimum
(``automatic-speech-recognition-with-past``: encoder_model.onnx, decoder_model_merged.onnx) and
quantized to int8 by speech-event's quantizer (``_int8``, as onnx-community names them). On 10
utterances it checks that the engine on that directory gives whisper.decode's tokens and no-speech
probability (temperature 0, language en, without timestamps), and the same text as the transformers
tokenizer decodes; and reports how many int8 decodings give the fp32 tokens. The directories are
left under /tmp/speech_event_whisper_optimum_*.
"""

import json
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, List

import numpy as np

from bench.parity.sentences import PARITY_SENTENCES, parity_audio
from bench.parity.whisper_parity import random_checkpoint
from speech_event.exporters.quantize import quantize_directory
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

# openai-whisper's parameter names -> transformers' (transformers' convert_openai_to_hf.py)
RENAMES = (
    ("blocks", "layers"),
    ("mlp.0", "fc1"),
    ("mlp.2", "fc2"),
    ("mlp_ln", "final_layer_norm"),
    (".attn.query", ".self_attn.q_proj"),
    (".attn.key", ".self_attn.k_proj"),
    (".attn.value", ".self_attn.v_proj"),
    (".attn_ln", ".self_attn_layer_norm"),
    (".attn.out", ".self_attn.out_proj"),
    (".cross_attn.query", ".encoder_attn.q_proj"),
    (".cross_attn.key", ".encoder_attn.k_proj"),
    (".cross_attn.value", ".encoder_attn.v_proj"),
    (".cross_attn_ln", ".encoder_attn_layer_norm"),
    (".cross_attn.out", ".encoder_attn.out_proj"),
    ("decoder.ln.", "decoder.layer_norm."),
    ("encoder.ln.", "encoder.layer_norm."),
    ("token_embedding", "embed_tokens"),
    ("encoder.positional_embedding", "encoder.embed_positions.weight"),
    ("decoder.positional_embedding", "decoder.embed_positions.weight"),
    ("ln_post", "layer_norm"),
)


def _renamed(name: str) -> str:
    for old, new in RENAMES:
        name = name.replace(old, new)
    return name


def tokenizer_files(tokenizer: Any, directory: Path) -> None:
    """transformers' WhisperTokenizer files for whisper's tokenizer: vocab.json and merges.txt from its
    tiktoken file (transformers' TikTokenConverter), its special tokens added in whisper's order."""
    import whisper
    from transformers import AddedToken, WhisperTokenizer
    from transformers.convert_slow_tokenizer import TikTokenConverter

    ranks_file = Path(whisper.__file__).parent / "assets" / "multilingual.tiktoken"
    vocabulary, merges = TikTokenConverter().extract_vocab_merges_from_model(str(ranks_file))
    staging = directory / "staging"
    staging.mkdir(parents=True)
    (staging / "vocab.json").write_text(json.dumps(vocabulary), encoding="utf-8")
    (staging / "merges.txt").write_text(
        "#version: 0.2\n" + "".join(f"{left} {right}\n" for left, right in merges), encoding="utf-8"
    )
    hf = WhisperTokenizer(str(staging / "vocab.json"), str(staging / "merges.txt"))
    specials = sorted(tokenizer.special_tokens.items(), key=lambda item: item[1])
    hf.add_tokens(
        [AddedToken(text, special=True, normalized=False) for text, _ in specials], special_tokens=True
    )
    wrong = [(text, token) for text, token in specials if hf.convert_tokens_to_ids(text) != token]
    if wrong:
        raise RuntimeError(f"special tokens at other ids than whisper's: {wrong[:5]}")
    hf.save_pretrained(str(directory))
    shutil.rmtree(staging)


def transformers_model(checkpoint: Path, tokenizer: Any, directory: Path) -> None:
    """The checkpoint as transformers' Whisper in ``directory``, with Hugging Face's generation config."""
    import torch
    from transformers import GenerationConfig, WhisperConfig, WhisperForConditionalGeneration

    saved = torch.load(str(checkpoint), map_location="cpu")
    dims = saved["dims"]
    suppress = {*tokenizer.non_speech_tokens, tokenizer.sot, tokenizer.translate, tokenizer.transcribe}
    suppress |= {tokenizer.sot_lm, tokenizer.sot_prev, tokenizer.no_speech}
    rules = {
        "suppress_tokens": sorted(suppress),
        "begin_suppress_tokens": [*tokenizer.encode(" "), tokenizer.eot],
    }
    config = WhisperConfig(
        vocab_size=dims["n_vocab"],
        num_mel_bins=dims["n_mels"],
        encoder_layers=dims["n_audio_layer"],
        encoder_attention_heads=dims["n_audio_head"],
        decoder_layers=dims["n_text_layer"],
        decoder_attention_heads=dims["n_text_head"],
        d_model=dims["n_text_state"],
        encoder_ffn_dim=4 * dims["n_audio_state"],
        decoder_ffn_dim=4 * dims["n_text_state"],
        max_source_positions=dims["n_audio_ctx"],
        max_target_positions=dims["n_text_ctx"],
        decoder_start_token_id=tokenizer.sot,
        bos_token_id=tokenizer.eot,
        eos_token_id=tokenizer.eot,
        pad_token_id=tokenizer.eot,
        **rules,
    )
    model = WhisperForConditionalGeneration(config).eval()
    state = {_renamed(name): tensor for name, tensor in saved["model_state_dict"].items()}
    missing, unexpected = model.model.load_state_dict(state, strict=False)
    if unexpected or [name for name in missing if not name.endswith("k_proj.bias")]:
        raise RuntimeError(f"weights not converted: missing {missing}, unexpected {unexpected}")
    model.proj_out.weight = model.model.decoder.embed_tokens.weight
    model.generation_config = GenerationConfig(
        decoder_start_token_id=tokenizer.sot,
        eos_token_id=tokenizer.eot,
        pad_token_id=tokenizer.eot,
        max_length=dims["n_text_ctx"],
        no_timestamps_token_id=tokenizer.no_timestamps,
        is_multilingual=True,
        lang_to_id={f"<|{code}|>": tokenizer.to_language_token(code) for code in ("en", "fr", "de", "sw")},
        task_to_id={"transcribe": tokenizer.transcribe, "translate": tokenizer.translate},
        **rules,
    )
    model.save_pretrained(str(directory))


def optimum_directory(checkpoint: Path, tokenizer: Any, work: Path) -> Path:
    """optimum's export of the checkpoint, its int8 files beside, as onnx-community publishes them."""
    from optimum.exporters.onnx import main_export

    source, exported = work / "transformers", work / "optimum"
    transformers_model(checkpoint, tokenizer, source)
    tokenizer_files(tokenizer, source)
    main_export(str(source), output=str(exported), task="automatic-speech-recognition-with-past")
    quantize_directory(exported)
    for quantized in exported.glob("*.int8.onnx"):  # onnx-community's names: encoder_model_int8.onnx
        quantized.rename(quantized.with_name(quantized.name.replace(".int8.onnx", "_int8.onnx")))
    return exported


def _whisper_decode(model: Any, audio: np.ndarray) -> Any:
    import whisper

    mel = whisper.log_mel_spectrogram(audio, model.dims.n_mels, padding=whisper.audio.N_SAMPLES)[:, :3000]
    options = whisper.DecodingOptions(language="en", without_timestamps=True, fp16=False, temperature=0.0)
    return whisper.decode(model, mel, options)


def main(shapes: List[str]) -> int:
    import whisper
    from transformers import WhisperTokenizer
    from whisper.tokenizer import get_tokenizer

    work = Path(tempfile.mkdtemp(prefix="speech_event_whisper_optimum_"))
    audio = parity_audio()
    tokenizer = get_tokenizer(True, num_languages=99, task="transcribe")
    all_same = True
    for shape in shapes or ["tiny", "base"]:
        started = time.perf_counter()
        checkpoint = random_checkpoint(shape, work / f"{shape}.pt")
        directory = optimum_directory(checkpoint, tokenizer, work / shape)
        print(
            f"{shape}: exported by optimum in {time.perf_counter() - started:.1f} s: "
            + ", ".join(sorted(path.name for path in directory.iterdir()))
        )
        model = whisper.load_model(str(checkpoint), device="cpu")
        hf_tokenizer = WhisperTokenizer.from_pretrained(str(directory))
        engines: Dict[str, WhisperRecognizer] = {
            precision: WhisperRecognizer(directory, "english", Runtime(int8=precision == "int8"))
            for precision in ("fp32", "int8")
        }
        matches, texts_same, int8_same, worst_no_speech, busy, seconds = 0, 0, 0, 0.0, 0.0, 0.0
        for sentence, samples in zip(PARITY_SENTENCES, audio):
            theirs = _whisper_decode(model, samples)
            started = time.perf_counter()
            ours = engines["fp32"].decode(samples)
            busy += time.perf_counter() - started
            seconds += samples.size / 16000
            same = ours.tokens == list(theirs.tokens)
            matches += same
            texts_same += (
                engines["fp32"].transcribe(samples).text
                == hf_tokenizer.decode(ours.tokens, skip_special_tokens=True).strip()
            )
            int8_same += engines["int8"].decode(samples).tokens == ours.tokens
            worst_no_speech = max(worst_no_speech, abs((ours.no_speech_prob or 0.0) - theirs.no_speech_prob))
            verdict = "same" if same else "DIFFERENT"
            print(f"  {sentence!r}: {verdict} ({len(theirs.tokens)} tokens from whisper)")
        print(
            f"{shape}: {matches} of {len(audio)} utterances give whisper's own tokens, {texts_same} the "
            f"transformers tokenizer's text; no_speech_prob differs by {worst_no_speech:.1e} at most; "
            f"int8 gives the fp32 tokens on {int8_same}; RTF {busy / seconds:.3f}",
            flush=True,
        )
        all_same &= matches == texts_same == len(PARITY_SENTENCES)
    return 0 if all_same else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
