"""The robot's interfaces around the pipeline: what other nodes call, read or keep.

``services`` (/speechEvent/set_enabled and set_language, with ``language_engines`` behind the
latter), ``action`` (recognise_speech), ``diagnostics`` (/diagnostics) and ``storage`` (each
utterance's audio and text on disk).
"""
