"""The errors the node's core raises at start-up; each message says what is wrong and what is allowed."""


class ConfigError(Exception):
    """A configuration that cannot be used; the message says where and what is allowed."""


class ModelError(Exception):
    """A model directory the engine cannot use; the message says what is wrong and what is expected."""


class StorageError(Exception):
    """A storage folder that cannot be made or written: said at start-up, before ROS."""


class GrammarError(ModelError):
    """A grammar that cannot be used (unreadable, malformed, words an engine cannot spell): a
    ModelError, since wherever an engine is built a grammar it cannot take stops it the same way."""
