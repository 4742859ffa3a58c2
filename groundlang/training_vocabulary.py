"""The vocabulary a learner is trained with: what it reads of its observations and of the domain's schema."""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Iterable
from importlib.resources import files
from pathlib import Path

from groundlang.logic.classes import domain_classes
from groundlang.logic.schema import domain_schema
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.encoding import Observation, machine_string
from groundlang.model.phrase_keys import PhraseKeys, bare_preposition, entity_words
from groundlang.model.interpretations import alignable_roles, bystander_roles
from groundlang.model.vocabulary import Vocabulary, class_token

__all__ = ["build_vocabulary", "palette_schema", "schema_names", "schema_words", "unlisted_schema_words",
           "word_files_beside"]


def palette_schema(library: TaskLibrary, palette):
    """The domain's schema with ``palette``'s values (its property PFs' families depend on them)."""
    return domain_schema(library, (palette.name, palette.all_values))


def build_vocabulary(observations: Iterable[Observation], palettes: Iterable, library: TaskLibrary,
                     word_lexicon, relational: bool = False, keys: PhraseKeys = PhraseKeys(),
                     start_role: bool = True, by_class: bool = True, names: bool = False) -> Vocabulary:
    """The vocabulary of a training set: its words, the preposition keys of its readings (and the bare
    prepositions the parse model generates), the tokens and roles of its interpretations, and every
    property PF and class the domain declares for ``palettes`` (a test layout may show values training
    never did). ``relational``: the tasks' tables span their relational roles too
    (``model.relational``; the parse model's ``relational_descriptions``). ``keys``: the marks of the
    preposition keys (``phrase_keys.PhraseKeys``); ``start_role``, ``by_class``: the bystanders' roles
    (``interpretations.bystander_roles``). ``names``: the vocabulary keeps the schema's names of its
    tokens (:func:`schema_names`) and knows their words (a language model's ``schema_names``)."""
    vocab = Vocabulary(lexicon=word_lexicon)
    vocab.add_tasks((task.name for task in library.tasks),
                    roles={task.name: alignable_roles(task, library.relational_pfs if relational else (),
                                                      start_role, by_class)
                           for task in library.tasks})
    tokens: list[str] = []
    roles: list[str] = []
    preps: list[str] = []
    counts: Counter = Counter()
    for obs in observations:
        vocab.add_words(obs.words)
        counts.update(obs.words)
        for reading in obs.readings:
            said = [p for p, _, _ in entity_words(reading.logical_form, word_lexicon, keys) if p is not None]
            preps.extend(said)
            preps.extend(b for p in said if (b := bare_preposition(p)) is not None)  # what the parse model generates
        for interp in obs.interpretations:
            tokens.extend(machine_string(interp))
            for rb in interp.roles:
                roles.append(rb.role)
                tokens.append(class_token(rb.cls))
                tokens.extend(rb.constraint_tokens + rb.kind_tokens)  # a user's PF may describe only bystanders
                if names:
                    vocab.kinds.update(dict.fromkeys((class_token(rb.cls), *rb.kind_tokens), rb.cls))
    # Every property PF the domain declares for the palettes seen (colours, shapes, a user's
    # sizes...) and every class: a layout of the test may have values training never saw.
    classes: list[str] = []
    for palette in palettes:
        schema = palette_schema(library, palette)
        if names:
            for token, (word, family) in schema_names(schema).items():
                vocab.names[token] = word
                vocab.name_families[token] = family
        tokens.extend(d.name for d in schema.pfs.values() if len(d.signature) == 1
                      and library.pf_roles.property_class(d.pf_class))
        classes.extend(schema.classes)
    tokens.extend(class_token(c) for c in dict.fromkeys(classes))
    if names:
        vocab.kinds.update({class_token(c): c for c in classes})
    tokens.extend(library.spatial_pfs)  # a layout of the test may have sides training never saw
    vocab.add_tokens(tokens)
    vocab.add_words(vocab.names.values())  # a name is a word before training says it: "the yellow room"
    vocab.add_roles(roles + list(bystander_roles(start_role, by_class)))
    vocab.add_preps(preps)
    vocab.read_misspellings(counts)
    return vocab


def word_files_beside(library: TaskLibrary) -> list[Path]:
    """The word file of each library file that has one: ``mine.words`` beside ``mine.lp`` (the package's
    own files too: ``logic/domains/williams2018.words``)."""
    out = []
    for source in library.sources:
        if source.name.startswith("groundlang.logic/"):
            path = Path(str(files("groundlang.logic"))) / source.name.removeprefix("groundlang.logic/")
        else:
            path = Path(source.name)
        words = path.with_suffix(".words")
        # Anything there by that name is the word file: a folder, a FIFO or a looping link is then refused
        # by the reader, as --lexicon refuses it, not silently passed over.
        if path.suffix == ".lp" and os.path.lexists(words):
            out.append(words)
    return out


def schema_names(schema) -> dict[str, tuple[str, str]]:
    """Token -> (the word the schema names it by, the family of names it is one of): a class token its
    class (``CLASS:door`` -> ``("door", "class")``), a property PF of one object its value and PF class
    (``toyIs(chair)`` -> ``("chair", "shape")``). Values in camelCase (``darkGray``) are not words anyone
    types and are left out, as in :func:`schema_words`."""
    out = {class_token(c): (c, "class") for c in schema.classes if c.isalpha() and c.islower()}
    for d in schema.pfs.values():
        functor, _, rest = d.term.partition("(")
        value = rest.rstrip(")")
        if len(d.signature) == 1 and value in schema.values.get(d.pf_class, ()) and value.isalpha() and value.islower():
            out[d.name] = (value, d.pf_class)
    return out


def unlisted_schema_words(library: TaskLibrary, palettes: Iterable, lexicon) -> dict[str, list[str]]:
    """The words the schemas of ``library`` with ``palettes`` name that ``lexicon`` does not list yet, by
    category: what a learner trained on states of those palettes adds to its parser ("ball" a noun, "lilac" a
    hue). Only unlisted ones: a value's name is not always a word of its category (williams2018 stores box
    sizes, "small", in the colour field)."""
    words: dict[str, list[str]] = {}
    for palette in palettes:
        for category, entries in schema_words(palette_schema(library, palette)).items():
            words.setdefault(category, []).extend(w for w in entries if not lexicon.listed(w))
    return words


def schema_words(schema) -> dict[str, list[str]]:
    """The words a domain's schema names: its classes and the values of attributes that name kinds (``kind/1``
    of ``domain.lp``: shapes) are nouns, the values of its other attributes (colours) hues (values written in
    camelCase, ``darkGray``, are not words anyone types and are left out)."""
    kinds = domain_classes().kinds
    nouns = [c for c in schema.classes] + [v for a, values in schema.values.items() if a in kinds for v in values]
    hues = [v for a, values in schema.values.items() if a not in kinds for v in values]
    return {category: [w for w in words if w.isalpha() and w.islower()]
            for category, words in (("NOUN", nouns), ("HUE", hues))}
