"""The grammar in force in a neural engine, and each grammar's phrases compiled once (to the
model's tokens): what the NeMo and Whisper engines' ``check_grammar`` and ``use_grammar`` share."""

from typing import Callable, Dict, Generic, Optional, TypeVar

from speech_event.grammar import Grammar

Compiled = TypeVar("Compiled")


class CompiledGrammars(Generic[Compiled]):
    """``compile`` raises GrammarError for a grammar the model cannot spell; a grammar is compiled
    once, when it is checked or put in force, and kept for when it comes back."""

    def __init__(self, compile: Callable[[Grammar], Compiled]) -> None:
        self._compile = compile
        self._compiled: Dict[Grammar, Compiled] = {}
        self.in_force: Optional[Grammar] = None

    def compiled(self, grammar: Grammar) -> Compiled:
        found = self._compiled.get(grammar)
        if found is None:
            found = self._compiled[grammar] = self._compile(grammar)
        return found

    def use(self, grammar: Optional[Grammar]) -> None:
        """Put ``grammar`` in force (None: free decoding), compiled first so that a refused one never is."""
        if grammar is not None:
            self.compiled(grammar)
        self.in_force = grammar
