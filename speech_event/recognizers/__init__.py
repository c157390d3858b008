"""Recognizers: adapters of the Recognizer port."""
