"""The base of the language models E | L, C: Dirichlet word distributions per semantic token and the
mixtures of tokens words are emitted from (``model.language_models`` lists the models)."""

from __future__ import annotations


import pyro
import pyro.distributions as dist
import torch

from groundlang.model.encoding import Batch, Encoder, Observation, token_exclusions
from groundlang.model.phrase_keys import PhraseKeys

# What an end habit's share is shrunk towards by one pseudo-demonstration (inference.end_habits EndHabits.rate):
# one that did not show it, or one at the relation's rate over all demonstrations.
HABIT_PRIORS = ("absent", "overall")
# The settings of every language model that act only when following (the posterior in a new layout, where the
# plan ends, how confident it is): training, and so any held-out likelihood, is the same whatever they are.
FOLLOWING_SETTINGS = ("achievable_goals", "expected_success", "step_cost", "end_habits", "moved_toys",
                      "habits_made_true", "bound_habits", "habit_prior", "success_confidence", "held_goals_confidence",
                      "other_starts")

__all__ = ["LanguageModel", "FOLLOWING_SETTINGS", "NULL_MIXTURE", "mixture_log_emissions", "gather_mixtures", "require_positive",
           "token_words", "word_meanings", "LEARNED_SHARE"]


class LanguageModel:
    """Base: Dirichlet word distributions per semantic token."""

    name = "base"
    # Whether interpretations enumerate binding constraints C (see model.interpretations).
    enumerates_constraints = True
    # Whether training starts from the bag of words' word distributions: an alignment model's MAP from a
    # flat start lands in poor local optima, as IBM Model 2 is classically started from Model 1.
    starts_from_bag_of_words = True
    # What the interpretations offer (model.interpretations.interpretations); the parse model has these
    # as settings, and its preposition keys' marks (phrase_keys).
    relation_words = False
    held_parts = False
    relational_descriptions = False
    start_role = True
    bystander_roles = True
    negated_verbs_frame = True
    mention_task_objects = True
    parser_weights = None  # overrides of the grammar's rule weights (grammar.parser.DEFAULT_WEIGHTS)

    def __init__(self, word_concentration: float = 1.05, null_token: bool = True, schema_names: bool = False,
                 achievable_goals: bool = True, expected_success: bool = True, step_cost: float = 0.005,
                 end_habits: bool = True, moved_toys: bool = False, habits_made_true: bool = False,
                 bound_habits: bool = True, habit_prior: str = "absent", success_confidence: bool = True,
                 held_goals_confidence: bool = False, other_starts: bool = True):
        """``schema_names``: a token says the word the domain's schema names it by (a class's name,
        "door"; an attribute value's, "chair", "red"; ``Vocabulary.names``) with a learned share
        ``name_share``, and its learned words otherwise: the names a domain's author gives are words
        for what they name, so a token training never names ("door") does not take a frequent word it
        could explain for free, a room is not called "chair", and a value training never showed ("the
        yellow room") is read by its name. ``achievable_goals``: a command asks for what can be done, so
        following it conditions the posterior on the goal holding in some state reachable from the start
        (where the whole state space is enumerated; ``Learner.posterior``). ``expected_success``: following
        ends where what was meant most probably holds, over the whole posterior, not only where its most
        probable goal does (``goal_plans.expected_success_states``); ``step_cost``, at least 0, is how much
        probability of success a step is worth there. ``end_habits``: there, each goal is weighed by what
        the training demonstrations of such goals also left true where they ended
        (:mod:`groundlang.inference.end_habits`); with ``moved_toys`` as well, by how often they moved a
        toy (a state where one moved weighs that rate). ``habits_made_true``: a relation weighs a state
        where the plan made one of its facts true (one that did not hold at the start), as demonstrations
        were counted, not wherever one of its facts holds. ``bound_habits``: a relation's fact weighs more
        where it is bound to the goal's objects as demonstrations showed (the agent in the room the toy
        was pushed into; ``EndHabits.weights``). ``habit_prior``: what a habit's share is shrunk towards
        by one pseudo-demonstration: ``"absent"``, one that did not show it (a habit is what demonstrations of
        such goals were seen to do), ``"overall"``, one at the relation's rate over all demonstrations
        (``EndHabits.rate``). ``success_confidence``: where following ends in a state chosen over the whole
        posterior (``expected_success``), its confidence is the posterior probability that what was meant
        holds there, ``sum_g P(g | words) [s satisfies g]`` (ending right of the chair satisfies "next to" as
        well), not only the probability of the goal said to be acted on (``FollowResult.confidence``).
        ``held_goals_confidence`` (off: ABLATIONS.md): with ``success_confidence``, the words' share on goals that already hold at
        the start (which following sets aside: they ask nothing) counts against that confidence, each such
        goal for where following ends only if it still holds there ("go to the blue room" said in it is not
        sure of walking to the only other room). ``other_starts``: a command given in several start states at
        once (``Learner.follow(..., other_starts=...)``, a Williams et al. command's other layouts) asks for
        a task that holds in none of them (:mod:`groundlang.other_starts`)."""
        # Dirichlet(1 + eps) MAP == EM with add-eps smoothing (Model 0's epsilon).
        require_positive(self.name, "word_concentration", word_concentration)
        self.word_concentration = word_concentration
        self.null_token = null_token
        self.schema_names = schema_names
        self.achievable_goals = achievable_goals
        if not 0.0 <= step_cost <= 1.0:  # NaN fails both; a step worth more than certain success is no cost
            raise ValueError(f"language model {self.name}: step_cost must be between 0 and 1 (probability of "
                             f"success per step), not {step_cost!r}")
        self.expected_success = expected_success
        self.step_cost = step_cost
        self.end_habits = end_habits
        self.moved_toys = moved_toys
        self.habits_made_true = habits_made_true
        self.bound_habits = bound_habits
        if habit_prior not in HABIT_PRIORS:
            raise ValueError(f"language model {self.name}: habit_prior must be one of {', '.join(HABIT_PRIORS)}, "
                             f"not {habit_prior!r:.40}")
        self.habit_prior = habit_prior
        self.success_confidence = success_confidence
        self.held_goals_confidence = held_goals_confidence
        self.other_starts = other_starts

    def settings(self) -> dict:
        return {"word_concentration": self.word_concentration, "null_token": self.null_token,
                "schema_names": self.schema_names, "achievable_goals": self.achievable_goals,
                "expected_success": self.expected_success, "step_cost": self.step_cost,
                "end_habits": self.end_habits, "moved_toys": self.moved_toys,
                "habits_made_true": self.habits_made_true, "bound_habits": self.bound_habits,
                "habit_prior": self.habit_prior, "success_confidence": self.success_confidence,
                "held_goals_confidence": self.held_goals_confidence, "other_starts": self.other_starts}

    def phrase_keys(self) -> PhraseKeys:
        """The marks of the noun phrases' preposition keys this model's batches are encoded with."""
        return PhraseKeys()

    # The type of this model's batches: the shared Batch, or a subclass holding the model's own fields.
    batch_type = Batch

    def encode(self, observations: list[Observation], vocab) -> Batch:
        """The batch this model reads: ``observations`` indexed with ``vocab`` under the model's settings."""
        enc = Encoder(observations, vocab)
        return enc.batch(self.batch_type, **self.encode_fields(enc))

    def encode_fields(self, enc: Encoder) -> dict:
        """This model's own fields of its batch (``batch_type``), which may also replace a shared one;
        ``enc`` holds the observations, the vocabulary and the mixture table to intern token sets in."""
        return {}

    def sample_globals(
        self, num_tokens: int, num_words: int, num_roles: int, num_preps: int, role_names: tuple[str, ...] = (),
        num_tasks: int = 0, offered: tuple[tuple[bool, ...], ...] = (), name_families: int = 0,
        prep_names: tuple[str, ...] = (),
    ) -> dict:
        with pyro.plate("tokens", num_tokens, dim=-1):
            phi = pyro.sample(
                "phi", dist.Dirichlet(torch.full((num_words,), self.word_concentration))
            )
        g = {"phi": phi}
        if self.schema_names and name_families:
            # Per family of names (classes, colours, shapes): P(a token says its name), P(it says one of
            # its learned words); a mixture, so EM stays exact. Per family, because a palette's names may
            # not be what people call its values (a room the palette names "red" that commands call
            # "orange") while its shapes' are.
            with pyro.plate("name_families", name_families, dim=-1):
                g["name_share"] = pyro.sample(
                    "name_share", dist.Dirichlet(torch.full((2,), NAME_SHARE_CONCENTRATION)))
        return g

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        """``log P(words_i | interpretation j)`` as ``[I, J]``, readings and alignments summed out."""
        raise NotImplementedError

    def alignment_probabilities(self, g: dict, batch: Batch, j: int, s: int) -> torch.Tensor | None:
        """For a model that aligns noun phrases with roles: ``[K, V]``, ``P(phrase type k aligns with role
        binding v | words, interpretation j, reading s)`` of the one command of ``batch``. None (the
        default): it aligns nothing."""
        return None

    def words_by_reading(self, g: dict, batch: Batch) -> tuple[torch.Tensor, torch.Tensor] | None:
        """For a model that reads the parser's readings: ``log P(words_i | j, reading s)`` as ``[I, J, S]``
        and the readings' prior logits ``[I, S]`` (the parser's, merged by structure), so the reading
        is a Pyro site of the generative model (``model.generative.instance_model``) and its posterior
        is Pyro's (``inference.joint.reading_posterior``). None (the default): no reading."""
        return None


# The model's tensors are float32: a concentration outside this range rounds to 0 or to infinity there.
CONCENTRATION_RANGE = (1e-30, 1e30)


def require_positive(model: str, name: str, value: float, added: bool = False) -> None:
    """A Dirichlet concentration within ``CONCENTRATION_RANGE``; with ``added``, a value added to one,
    which may be 0."""
    low, high = (0.0 if added else CONCENTRATION_RANGE[0]), CONCENTRATION_RANGE[1]
    if low <= value <= high:  # NaN fails both comparisons
        return
    rule = (f">= 0 (added to a Dirichlet concentration), at most {high:g}" if added else
            f"> 0 (a Dirichlet concentration), at most {high:g} and at least {low:g}")
    raise ValueError(f"language model {model}: {name} must be {rule}, not {value!r}")


NULL_MIXTURE = 0  # encode() interns the {NULL} mixture first


# The prior of ``name_share``: flat but for one pseudo-count each way, so the share is learned.
NAME_SHARE_CONCENTRATION = 2.0


def token_words(g: dict, token_name: torch.Tensor, excluded: torch.Tensor, family: torch.Tensor) -> torch.Tensor:
    """``P(word | token)`` as ``[T, W]``: ``phi``, or with ``name_share`` (``schema_names``) a named
    token's name mixed with its ``phi`` row. ``token_name`` ``[T]``: the word each token is named by, or
    -1; ``excluded`` ``[T, W]``: the words a token does not say (``Vocabulary.token_names``,
    ``encoding.token_exclusions``); ``family`` ``[T]``: each token's family of names, or -1
    (``Vocabulary.token_families``)."""
    phi = g["phi"]
    if "name_share" not in g:
        return phi
    names = token_name
    named = names >= 0
    said = torch.nn.functional.one_hot(names.clamp_min(0), phi.shape[-1]).to(phi.dtype)
    # Mutual exclusivity: a named token does not learn another kind's name ("chair" is not a word for
    # a room); that share of its learned words is lost, as a role an interpretation lacks is, so EM
    # stays exact and drives it to the prior's pseudo-count.
    share = g["name_share"][family.clamp_min(0)]  # [T, 2]
    return torch.where(named[:, None], share[:, :1] * said + share[:, 1:] * phi.masked_fill(excluded, 0.0), phi)


def mixture_log_emissions(g: dict, batch: Batch) -> torch.Tensor:
    """``log P(word w | mixture x)`` as ``[X, W]``: the log is taken once per word of the vocabulary,
    not once per word of every instance."""
    emit = batch.mixtures @ token_words(g, batch.token_name, batch.token_excluded, batch.token_family)  # [X, W]
    return emit.clamp_min(1e-30).log()


def gather_mixtures(log_emit: torch.Tensor, mix_ids: torch.Tensor, uniq: torch.Tensor) -> torch.Tensor:
    """``log_emit [X, W]`` at mixtures ``mix_ids [I, ...]`` and each instance's words ``uniq [I, U]`` ->
    ``[I, ..., U]``, with no ``[X, I, U]`` table in between."""
    I, U = uniq.shape
    flat = mix_ids.reshape(I, -1)  # [I, Q]
    out = log_emit[flat[:, :, None], uniq[:, None, :]]  # [I, Q, U]
    return out.reshape(*mix_ids.shape, U)


# A token's row of P(word | token) is learned when its largest entry is at least this many times the
# uniform share: an untrained row keeps its flat prior exactly, and one that spreads over a few synonyms
# in a small vocabulary ("go", "walk", "enter", "room" for agentToRoom among 16 words) is learned.
LEARNED_SHARE = 2.0


def word_meanings(g: dict, vocab, top: int = 3) -> dict[str, list[tuple[str, float]]]:
    """Each known word of ``vocab``'s most probable meanings, ``P(token | word)``, under the globals ``g``:
    what a token says is its learned words and, under ``schema_names``, its name. The prior over tokens
    is uniform over the tokens training used: a token with a flat distribution is left out, so that it
    does not dilute the table."""
    phi = token_words(g, torch.tensor(vocab.token_names()), token_exclusions(vocab),
                      torch.tensor(vocab.token_families()))  # [S, W]
    learned = phi.max(-1).values > LEARNED_SHARE / phi.shape[1]
    meaning = phi * learned[:, None]
    meaning = meaning / meaning.sum(0, keepdim=True).clamp_min(1e-30)
    out = {}
    for w, word in enumerate(vocab.words[1:], start=1):
        if word in vocab.aliases:
            continue  # read as another word: its own column was never trained
        order = torch.argsort(meaning[:, w], descending=True)[:top]
        out[word] = [(vocab.tokens[int(s)], float(meaning[s, w])) for s in order]
    return out
