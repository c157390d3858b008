"""Parity of the Whisper engine with openai-whisper itself (a tool, not CI): needs torch and
openai-whisper.

    /tmp/nemo/bin/pip install torch openai-whisper      # any venv with both
    PYTHONPATH=. /tmp/nemo/bin/python -m bench.parity.whisper_parity [tiny base]

Builds randomly initialised Whisper models of the tiny and base shapes (whisper's own
ModelDimensions, the multilingual vocabulary), saves each as a checkpoint, exports it with
``speech-event export-whisper`` and checks, on 10 utterances, that the engine's tokens and
no-speech probability equal whisper.decode's (temperature 0, language en, without timestamps) on
whisper's own log-mel of the same audio, and that the engine's log-mel equals
whisper.log_mel_spectrogram's. Random weights would never end a sentence: the end-of-text token's
embedding is set along the final layer norm's bias, so it wins after some tokens (see EOT_LENGTH). Prints the
engine's real-time factor too; the exported directories are left under /tmp/speech_event_whisper_*.
"""

import sys
import tempfile
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any, Dict, List

import numpy as np

from bench.parity.sentences import PARITY_SENTENCES, parity_audio
from speech_event.exporters.whisper import export
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

SHAPES: Dict[str, Dict[str, int]] = {
    "tiny": {
        "n_audio_state": 384,
        "n_audio_head": 6,
        "n_audio_layer": 4,
        "n_text_state": 384,
        "n_text_head": 6,
        "n_text_layer": 4,
    },
    "base": {
        "n_audio_state": 512,
        "n_audio_head": 8,
        "n_audio_layer": 6,
        "n_text_state": 512,
        "n_text_head": 8,
        "n_text_layer": 6,
    },
    "small": {
        "n_audio_state": 768,
        "n_audio_head": 12,
        "n_audio_layer": 12,
        "n_text_state": 768,
        "n_text_head": 12,
        "n_text_layer": 12,
    },
}
# The end-of-text token's embedding, along the final layer norm's bias, as long as this many times
# the others (scaled down, so a token's own embedding does not make it repeat): sentences of about
# 90 to 150 varied tokens, then the end (measured on the tiny shape; 1.0 ends them at once).
EOT_LENGTH = 0.9
LN_BIAS = 3.0
EMBEDDING_SCALE = 0.1


def random_checkpoint(shape: str, path: Path) -> Path:
    import torch
    from whisper.model import ModelDimensions, Whisper

    torch.manual_seed(0)
    dims = ModelDimensions(n_mels=80, n_audio_ctx=1500, n_vocab=51865, n_text_ctx=448, **SHAPES[shape])
    model = Whisper(dims)
    with torch.no_grad():
        # whisper leaves the text decoder's positional embedding uninitialised (torch.empty)
        model.decoder.positional_embedding.copy_(torch.randn(dims.n_text_ctx, dims.n_text_state))
        direction = torch.nn.functional.normalize(torch.randn(dims.n_text_state), dim=0)
        model.decoder.ln.bias.copy_(LN_BIAS * direction)
        model.decoder.token_embedding.weight.mul_(EMBEDDING_SCALE)
        spread = float(model.decoder.token_embedding.weight.norm(dim=1).mean())
        model.decoder.token_embedding.weight[50257] = direction * spread * EOT_LENGTH  # eot
    torch.save({"dims": asdict(dims), "model_state_dict": model.state_dict()}, path)
    return path


def _whisper_decode(model: Any, audio: np.ndarray) -> Any:
    import whisper

    mel = whisper.log_mel_spectrogram(audio, model.dims.n_mels, padding=whisper.audio.N_SAMPLES)[:, :3000]
    options = whisper.DecodingOptions(language="en", without_timestamps=True, fp16=False, temperature=0.0)
    return whisper.decode(model, mel, options), mel.numpy()


def main(shapes: List[str]) -> int:
    import whisper

    work = Path(tempfile.mkdtemp(prefix="speech_event_whisper_"))
    audio = parity_audio()
    all_same = True
    for shape in shapes or ["tiny", "base"]:
        checkpoint = random_checkpoint(shape, work / f"{shape}.pt")
        model = whisper.load_model(str(checkpoint), device="cpu")
        parameters = sum(p.numel() for p in model.parameters())
        started = time.perf_counter()
        export(str(checkpoint), work / shape, {})
        print(
            f"{shape}: {parameters / 1e6:.1f} M parameters, exported in {time.perf_counter() - started:.1f} s"
        )
        engine = WhisperRecognizer(work / shape, "english")
        matches, worst_mel, worst_no_speech, busy, seconds = 0, 0.0, 0.0, 0.0, 0.0
        for sentence, samples in zip(PARITY_SENTENCES, audio):
            theirs, their_mel = _whisper_decode(model, samples)
            worst_mel = max(worst_mel, float(np.abs(whisper_log_mel(samples, 80) - their_mel).max()))
            started = time.perf_counter()
            ours = engine.decode(samples)
            busy += time.perf_counter() - started
            seconds += samples.size / 16000
            same = ours.tokens == list(theirs.tokens)
            matches += same
            worst_no_speech = max(worst_no_speech, abs((ours.no_speech_prob or 0.0) - theirs.no_speech_prob))
            verdict = "same" if same else "DIFFERENT"
            print(f"  {sentence!r}: {verdict} ({len(theirs.tokens)} tokens from whisper)")
        print(
            f"{shape}: {matches} of {len(audio)} utterances give whisper's own tokens; log-mel differs "
            f"by {worst_mel:.1e} at most, no_speech_prob by {worst_no_speech:.1e}; RTF {busy / seconds:.3f}",
            flush=True,
        )
        all_same &= matches == len(PARITY_SENTENCES)
    return 0 if all_same else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
