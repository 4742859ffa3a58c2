"""Sub-commands of the ``groundlang`` CLI, one module each (see groundlang/cli.py).

Names the parsers need are kept here, free of torch, so that building the
parser (``groundlang --help``) imports nothing heavy; a test checks that they
match the library's.
"""

LANGUAGE_MODEL_NAMES = ("bow", "ibm2", "parse")  # == tuple(groundlang.model.language_models.LANGUAGE_MODELS)


def add_language_model_settings(parser) -> None:
    """``--lm-setting KEY=VALUE`` (repeatable): a keyword of the language model, for ablations."""
    parser.add_argument(
        "--lm-setting", metavar="KEY=VALUE", action="append", default=[], dest="lm_settings",
        help="a setting of the language model, e.g. mention_phrases=any or argument_bonus=0 (repeatable; "
             "VALUE is read as JSON: numbers, true, false, null, else text)",
    )


def language_model_settings(pairs: list[str]) -> dict:
    """``["argument_bonus=0", "mention_phrases=any"]`` -> ``{"argument_bonus": 0, "mention_phrases": "any"}``.
    Raises ValueError for an item without ``=``."""
    import json

    settings = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        text = text.strip()
        if not sep or not key.strip():
            raise ValueError(f"--lm-setting {pair!r}: expected KEY=VALUE, e.g. mention_phrases=any")
        try:
            value = json.loads(text)
        except ValueError:
            value = text
        settings[key.strip()] = value
    return settings
