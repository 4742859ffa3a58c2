"""Sub-commands of the ``groundlang`` CLI, one module each (see groundlang/cli.py).

Names the parsers need are kept here, free of torch, so that building the
parser (``groundlang --help``) imports nothing heavy; a test checks that they
match the library's.
"""

LANGUAGE_MODEL_NAMES = ("bow", "ibm2", "parse")  # == tuple(groundlang.model.language_models.LANGUAGE_MODELS)
