"""Semantic parsing: English commands to logical forms with probabilities (the paper's SP component).

``parse(command)`` gives the readings of a command, most probable first; see grammar/parser.py for the
pipeline and grammar/logical_form.py for what a reading holds. The words the parser knows are data:
``Lexicon`` reads closed-class English from ``english.words`` and a domain's words from word files.
"""

from .lexicon import Lexicon, LexiconError, SemanticLexicon
from .logical_form import Clause, Entity, LogicalForm, Reading, Relation
from .parser import DEFAULT_WEIGHTS, ParseError, parse, tokenise

__all__ = [
    "DEFAULT_WEIGHTS", "Clause", "Entity", "Lexicon", "LexiconError", "LogicalForm", "ParseError", "Reading",
    "Relation", "SemanticLexicon", "parse", "tokenise",
]
