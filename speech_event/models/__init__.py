"""Published model directories: ``pull`` fetches one from the Hugging Face Hub, ready for the node.

Apart from the exporters (``speech_event.exporters``, which need torch and NeMo or whisper on a
workstation): this needs only huggingface_hub (the ``pull`` extra), and can run on the robot.
"""
