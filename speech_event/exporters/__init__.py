"""Model exporters: the only code that needs torch, NeMo or openai-whisper (the ``export`` extra).

``nemo`` writes a NeMo checkpoint's ONNX directory, ``whisper`` a Whisper checkpoint's; the
engines in ``speech_event.recognizers`` read those directories with numpy and onnxruntime only.
"""
