"""The language models E | L, C by name: the registry that learners, saved models and ablations use.

Each model declares its global parameters as Pyro sample sites with
Dirichlet (or other) priors and computes, from them, the table
``log P(words_i | interpretation j)`` of shape ``[I, J]``. No discrete latent
is sampled here: alignments are summed out exactly inside the table, and the
interpretation (and, for the parse model, the reading) is enumerated by the
model in :mod:`groundlang.model.generative`. One module per model:

- ``bow``: the bag of words (``model.bag_of_words``; the paper's Model 0 is its special case);
- ``ibm2``: IBM Model 2 over a machine string (``model.ibm2``);
- ``parse``: words generated through the logical form (``model.parse_aligned``).
"""

from __future__ import annotations

import inspect
import math

from groundlang.model.bag_of_words import BagOfWords
from groundlang.model.ibm2 import IBMModel2
from groundlang.model.language_model_base import NULL_MIXTURE, LanguageModel, mixture_log_emissions
from groundlang.model.parse_aligned import ParseAligned

__all__ = ["LanguageModel", "BagOfWords", "IBMModel2", "ParseAligned", "LANGUAGE_MODELS", "get_language_model",
           "register_language_model", "setting_names", "setting_value", "NULL_MIXTURE", "mixture_log_emissions"]


LANGUAGE_MODELS = {"bow": BagOfWords, "ibm2": IBMModel2, "parse": ParseAligned}


def register_language_model(model: type[LanguageModel]) -> type[LanguageModel]:
    """Make a language model available by its ``name`` (``Learner("mine")``, saved models, ablations);
    usable as a class decorator. A model is a :class:`LanguageModel` subclass: its globals as Pyro
    sites (``sample_globals``), ``log P(words | interpretation)`` (``log_likelihood``) and, if it
    reads parses, ``words_by_reading``. ValueError for a name taken by another model."""
    if not (isinstance(model, type) and issubclass(model, LanguageModel)) or model is LanguageModel:
        raise TypeError(f"register_language_model: expected a LanguageModel subclass, got {model!r}")
    known = LANGUAGE_MODELS.get(model.name)
    if known is not None and known is not model:
        raise ValueError(f"a language model called {model.name!r} exists already ({known.__qualname__})")
    LANGUAGE_MODELS[model.name] = model
    return model


def get_language_model(name: str, **settings) -> LanguageModel:
    """The language model ``name`` with ``settings`` (its constructor's keywords, e.g.
    ``get_language_model("parse", mention_phrases="any")``). Raises ValueError naming the model
    and what it takes for an unknown name, an unknown setting or a value of the wrong kind."""
    params = _parameters(name)
    for key, value in settings.items():
        if key not in params:
            raise ValueError(f"language model {name} has no setting {key!r}; its settings: {', '.join(params)}")
        problem = _setting_problem(params[key], value)
        if problem:
            raise ValueError(f"language model {name}, setting {key}: {problem}")
    # A whole number typed for a real-valued setting ("word_concentration=2") is that real: as an int it would
    # make an integer tensor, which a Dirichlet cannot take.
    settings = {key: float(value) if _real_valued(params[key]) and type(value) is int else value
                for key, value in settings.items()}
    return LANGUAGE_MODELS[name](**settings)


def _real_valued(param: inspect.Parameter) -> bool:
    return isinstance(param.default, float) or "float" in str(param.annotation)


def setting_value(text: str) -> object:
    """A setting's value as a user writes it (``--lm-setting``, ``--switch``): JSON where it reads as JSON
    (``0.5``, ``true``, ``[1, 2]``), else the text itself (``any``). ValueError for JSON nested too deeply
    to read (the decoder recurses once per level)."""
    import json

    try:
        return json.loads(text, parse_int=_bounded_int)
    except RecursionError:
        raise ValueError(f"{text[:20]}...: nested too deeply to be a setting") from None
    except _TooLong as exc:
        raise ValueError(f"{text[:20]}...: a number of {exc.args[0]} digits; no setting takes one beyond a "
                         f"float's range") from None
    except ValueError:
        return text


class _TooLong(Exception):
    """A whole number in a setting's JSON too long to be a float (its digit count)."""


def _bounded_int(digits: str) -> int:
    # float() of a whole number beyond 1e308 overflows, where the model would use it; refused as it is read.
    if len(digits.lstrip("-")) > 308:
        raise _TooLong(len(digits.lstrip("-")))
    return int(digits)


def setting_names(name: str) -> tuple[str, ...]:
    """The settings (constructor keywords) language model ``name`` takes."""
    return tuple(_parameters(name))


def _parameters(name: str) -> dict[str, inspect.Parameter]:
    """Constructor keyword -> its parameter, for language model ``name``; ValueError for an unknown name."""
    if name not in LANGUAGE_MODELS:
        raise ValueError(f"unknown language model {name!r}; expected one of {', '.join(LANGUAGE_MODELS)}")
    return {k: p for k, p in inspect.signature(LANGUAGE_MODELS[name].__init__).parameters.items() if k != "self"}


def _setting_problem(param: inspect.Parameter, value) -> str | None:
    """What is wrong with ``value`` for a constructor keyword, judged by its default and annotation."""
    default, optional = param.default, "None" in str(param.annotation)
    if value is None:
        return None if optional or default is None else "None is not allowed here"
    if isinstance(default, bool):
        return None if isinstance(value, bool) else f"expected true or false, not {value!r}"
    if "dict" in str(param.annotation):  # checked by the model itself, which knows the keys
        return None if isinstance(value, dict) else f"expected names with values, e.g. {{\"name\": 1.0}}, not {value!r}"
    if isinstance(default, (int, float)) or default is None:
        try:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        except OverflowError:  # a whole number beyond a float's range (given in Python, not read from JSON)
            return f"expected a number within a float's range, not one of {len(str(abs(value)))} digits"
        return None if ok else f"expected a number, not {value!r}"
    if isinstance(default, str):
        return None if isinstance(value, str) else f"expected a string, not {value!r}"
    return None
