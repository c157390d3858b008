"""Published model directories: ``pull`` fetches one from the Hugging Face Hub, ready for the node.

Apart from the exporters that need torch and NeMo or whisper on a workstation: this needs
huggingface_hub, and onnx to convert a faster-whisper model with export-whisper's converter (both
the ``pull`` extra), and can run on the robot.
"""
