class ModelError(Exception):
    """A model directory the engine cannot use; the message says what is wrong and what is expected."""
