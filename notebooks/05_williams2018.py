# %% [markdown]
# # 05 · What was learned from the Williams et al. (2018) corpus
#
# The Cleanup World corpus of Williams, Gopalan, Rhee and Tellex (ICRA 2018) gives each command three (start, end) pairs, each in its own layout, and no trajectory (README, "The Williams et al. (2018) corpus"). This notebook trains a learner on it and looks at what it learned for four phrases: **"left of"**, **"next to"**, **"largest"** and **"the room with the chair"**:
#
# 1. the lexicon entries: what the learned lexicon says the words mean (`Learner.lexicon`, as `groundlang lexicon MODEL` prints it, each meaning explained from the domain's schema by `groundlang.wording.token_meanings`), and, for the relations, what the prepositions say of the task;
# 2. the posterior over interpretations of one command in two of its layouts, beside what its pairs show.
#
# The corpus is not part of the repository; it is read from `../shared/data/williams2018/train` beside the repository, or from the folder `GROUNDLANG_WILLIAMS` names. Without `GROUNDLANG_QUICK` the learner trains on all 1619 commands, as `groundlang train ../shared/data/williams2018/train -o MODEL` does (the README gives the time it takes); in quick mode (`GROUNDLANG_QUICK=1`, as in CI) on the first ten commands with each of the four phrases and every 50th command besides. Where the corpus is absent it says so and shows the same on the project's own small `.bdm` fixtures (`tests/fixtures/williams2018`: `small.bdm`, and `phrases/phrases.bdm` for the phrases `small.bdm` lacks), where the figures show the mechanism only.

# %%
import os
QUICK = os.environ.get("GROUNDLANG_QUICK") == "1"  # CI: smaller work, same story
# %matplotlib inline
import time
from collections import Counter
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import groundlang
from groundlang.animation import posterior_bar_chart
from groundlang.bdm_check import default_library
from groundlang.learner import Learner
from groundlang.logic.atoms import format_goal
from groundlang.logic.schema import domain_schema
from groundlang.pair_corpus import read_pair_corpus, training_instances
from groundlang.pair_tasks import pair_task
from groundlang.render import draw_state
from groundlang.wording import token_meanings

PHRASES = ["left of", "next to", "largest", "room with the chair"]
REPOSITORY = Path(groundlang.__file__).resolve().parent.parent
CORPUS = Path(os.environ.get("GROUNDLANG_WILLIAMS", REPOSITORY.parent / "shared" / "data" / "williams2018" / "train"))
FIXTURES = REPOSITORY / "tests" / "fixtures" / "williams2018"

library = default_library()  # logic/domains/williams2018.lp: its relations, superlatives and tasks
if CORPUS.is_dir():
    everything = read_pair_corpus(CORPUS).commands
    source = f"the Williams et al. corpus ({CORPUS})"
else:
    everything = (read_pair_corpus(FIXTURES / "small.bdm").commands
                  + read_pair_corpus(FIXTURES / "phrases").commands)
    print(f"The Williams et al. corpus is absent (looked for {CORPUS}; it is not part of the repository).\n"
          f"Showing the same on the project's own fixtures in {FIXTURES}: {len(everything)} commands, so the "
          "figures below show the mechanism, not what the corpus teaches.")
    source = "the project's fixtures"


def has(command, phrase):
    return phrase in command.text.lower()


if QUICK and CORPUS.is_dir():
    # Enough commands of each phrase to learn it, and every 50th other command for the rest of the language.
    picked = {id(c): c for phrase in PHRASES for c in [c for c in everything if has(c, phrase)][:10]}
    picked.update((id(c), c) for c in everything[::50])
    commands = [c for c in everything if id(c) in picked]
else:
    commands = everything
print(f"{len(commands)} of {len(everything)} commands of {source}" + (" (quick mode)" if QUICK else ""))
print("commands with each phrase:", {p: sum(has(c, p) for c in commands) for p in PHRASES})

# %% [markdown]
# ## Training from start and end states
#
# Each command becomes one training instance whose three pairs are evidence of one lifted meaning, each grounded in its own layout (`pair_corpus.training_instances`, `--layouts shared`): the behaviour term is the likelihood of each end state under each grounded task.

# %%
started = time.perf_counter()
made = training_instances(commands, library, skip_inconsistent=True)
learner = Learner(library=library, cache_dir=False).fit(made.instances)
skipped = made.skipped_counts()
print(f"trained on {len(made.instances)} commands ({sum(len(i.pairs) for i in made.instances)} pairs) "
      f"in {time.perf_counter() - started:.0f} s; pairs skipped: {skipped or 'none'}")

# %% [markdown]
# ## The lexicon entries
#
# `Learner.lexicon` gives each word its most probable meanings, `P(token | word)`: a PF the word says of an object (`roomIsLargest`), a class it names (`CLASS:toy`), a lifted task (`agentLeftOfToy`), or `NULL`. Below it, each meaning shown is explained in words read from the domain's schema, as `groundlang lexicon` prints them.

# %%
WORDS = ["left", "next", "largest", "room", "with", "chair"]
lexicon = learner.lexicon(top=3)
for word in WORDS:
    meanings = lexicon.get(word)
    print(f"{word:9s}", ", ".join(f"{t} {p:.2f}" for t, p in meanings) if meanings else "(not a word of the vocabulary)")
schema = domain_schema(library, "williams2018")
explained = token_meanings((t for w in WORDS for t, _ in lexicon.get(w, [])), [schema], library.phrases)
print("\nwhat the meanings are:")
for token, text in explained.items():
    print(f"  {token:26s} {text}")

known = [w for w in WORDS if w in lexicon]
tokens = list(dict.fromkeys(t for w in known for t, _ in lexicon[w]))
table = np.array([[dict(lexicon[w]).get(t, 0.0) for t in tokens] for w in known])
fig, ax = plt.subplots(figsize=(1.0 + 0.55 * len(tokens), 0.6 + 0.45 * len(known)))
ax.imshow(table, cmap="Blues", vmin=0, vmax=1, aspect="auto")
ax.set_xticks(range(len(tokens)), tokens, rotation=45, ha="right"); ax.set_yticks(range(len(known)), known)
for (i, j), p in np.ndenumerate(table):
    if p > 0:
        ax.text(j, i, f"{p:.2f}", ha="center", va="center", fontsize=7)
ax.set_title("P(meaning | word), top 3 per word"); fig.tight_layout()

# %% [markdown]
# ### What the prepositions say
#
# A relation is said by a preposition: the grammar reads "to the left of", "left of" and "next to" as one preposition each (`grammar/english.words`), so the relation is said by the preposition, not by "left": an entry of "left" above, where there is one, comes from its other uses ("the top left room", "on your left side"), and one of "next" from readings that split "next to". The parse model generates each phrase's preposition given the lifted task, `P(preposition | L)` (`preposition_concentration`, `model/parse_aligned.py`). Its learned table is the `preposition` entry of `Learner.globals` (`[lifted tasks, prepositions]`, in the order of `Learner.vocab.tasks` and `Learner.vocab.preps`). The model's prior over lifted tasks is uniform, so `P(L | preposition)` is that table normalised over tasks (`preposition_table` of `model/prepositions.py`; `groundlang lexicon MODEL --prepositions` prints it). Shown: the prepositions training gave mass to (the rule `Learner.lexicon` uses for words).

# %%
from groundlang.model.prepositions import preposition_table

tasks, preps, given = preposition_table(learner.globals, learner.vocab)  # given: P(L | preposition) [tasks, preps]
print(f"{'preposition':22s}", "  ".join(f"{t:>15s}" for t in tasks))
for k, prep in enumerate(preps):
    print(f"{prep:22s}", "  ".join(f"{float(given[t, k]):15.2f}" for t in range(len(tasks))))
fig, ax = plt.subplots(figsize=(1.5 + 0.9 * len(tasks), 0.8 + 0.35 * len(preps)))
ax.imshow(given.T.numpy(), cmap="Blues", vmin=0, vmax=1, aspect="auto")
ax.set_xticks(range(len(tasks)), tasks, rotation=30, ha="right")
ax.set_yticks(range(len(preps)), preps)
ax.set_title("P(lifted task | preposition)"); fig.tight_layout()

# %% [markdown]
# ### Where demonstrators stopped: end habits
#
# A demonstrator stops where the goal holds, and often where more holds too. Training counts, per (start, end) pair, the relations of which some fact holds at its end and not at its start; `Learner.habits.table()` gives `q(R | L)`, how often a pair whose new facts include relation `L` also shows `R` (`inference/end_habits.py`). Following weighs each goal's states by them, where they can hold with the goal (`end_habits`, README, Williams section).

# %%
table = learner.habits.table(learner.lm.habit_prior)  # shrunk as following shrinks them
relations = sorted(table)
print(f"{'goal relation L':18s}", "  ".join(f"{r:>15s}" for r in relations))
for given in relations:
    print(f"{given:18s}", "  ".join(f"{table[given].get(r, float('nan')):15.2f}" for r in relations))

# %% [markdown]
# Habits bound to the goal's objects (`bound_habits`): `R[i]=L[j]` counts pairs where a new fact of `R` has as its argument `i` the argument `j` of a new fact of `L`. Its rate `q_b` is at most `q(R | L)`, the rate of any new fact of `R`; what it says is their ratio, the share of those facts bound so. `agentInRoom[1]=toyInRoom[1]`: of the pairs that pushed a block into a room and left the agent in a room it was not in, the share where that room is the block's. Following weighs a state where only another fact of `R` holds by `1 - q_b` instead of 1. A binding through the one agent (`agentInRoom[0]=agentNextToToy[0]`) holds wherever both relations do; following skips such bindings, and they are left out here.

# %%
bound = learner.habits.bound_table(learner.lm.habit_prior)
print(f"{'bound habit':40s} {'q_b':>6s} {'q(R|L)':>7s} {'share':>6s}")
for name in sorted(bound):
    relation, _, other = name.partition("=")
    if relation.endswith("[0]") and other.endswith("[0]") and relation.startswith("agent") and other.startswith("agent"):
        continue  # bound through the agent: says nothing beyond the two relations
    q = learner.habits.rate(relation.split("[")[0], frozenset([other.split("[")[0]]), learner.lm.habit_prior)
    print(f"{name:40s} {bound[name]:6.3f} {q:7.3f} {bound[name] / q:6.2f}")

# %% [markdown]
# ## One command in two of its layouts
#
# The most common text with "left of" among the training commands, read in its first two layouts. `Learner.posterior` is the posterior from the words alone (the pairs are not consulted); beside it, what the command's three pairs show (`pair_tasks.pair_task`, the corpus README's rule: the lifted facts that hold in every end state and not in every start state).


# %%
def example(phrase):
    """A command with the most common text containing ``phrase`` whose first two layouts are 8x8 grids
    (in a 16x16 layout with three blocks, grouping goals by their outcome samples the world: slower)."""
    counts = Counter(c.text for c in commands if has(c, phrase))
    for text, _ in counts.most_common():
        for c in commands:
            if c.text == text and len(c.pairs) >= 2 and all(p.start.layout.width <= 9 for p in c.pairs[:2]):
                return c
    return None


def shown_task(command):
    shown = sorted(map(str, pair_task([(p.start, p.end) for p in command.pairs], library)))
    return ", ".join(shown) or "(none: no fact holds in every end state and not in every start state)"


command = example("left of")
print(f"{command.text!r} ({command.path.name}, line {command.line}); its pairs show: {shown_task(command)}")
fig, axes = plt.subplots(2, 3, figsize=(15, 7.5), gridspec_kw={"width_ratios": [1, 1, 1.4]})
for k, (row, pair) in enumerate(zip(axes, command.pairs[:2]), start=1):
    posterior = learner.posterior(command.text, pair.start)
    print(f"\nlayout {k} (line {pair.line}); goal acted on: {format_goal(posterior.best_goal)}, "
          f"confidence {posterior.confidence:.2f}")
    print(posterior.table(5))
    draw_state(pair.start, ax=row[0], title=f"layout {k}: start", legend=False)
    draw_state(pair.end, ax=row[1], title=f"layout {k}: end (no path between: the corpus has none)")
    posterior_bar_chart(posterior, kind="goals", top=5, ax=row[2])
fig.tight_layout()

# %% [markdown]
# ### The four phrases
#
# The same for a command of each phrase: the lifted task the words make most probable in each of its first two layouts, and what its pairs show. By default "the room with the chair" is not read as a relation (`relational_descriptions` is off: README, the Williams section), so the words do not single out the room that holds the chair; what the pairs show is printed beside it, the room said by what it holds (`agentInRoom(agent, toyInRoom(toyIsChair, _))`), as the corpus README judges.

# %%
for phrase in PHRASES:
    c = example(phrase)
    if c is None:
        print(f"{phrase!r}: no training command in 8x8 layouts has it")
        continue
    print(f"{phrase!r}: {c.text!r} ({c.path.name}, line {c.line})")
    for k, pair in enumerate(c.pairs[:2], start=1):
        posterior = learner.posterior(c.text, pair.start)
        lifted, p_lifted = next(iter(posterior.lifted_tasks().items()))
        p, best = posterior.ranked()[0]
        described = " ∧ ".join(map(str, best.constraint.atoms)) or "(none)"
        print(f"    layout {k}: {lifted} {p_lifted:.2f}; most probable interpretation {format_goal(best.goal)} "
              f"({p:.2f}), binding constraint {described}")
    print(f"    its pairs show: {shown_task(c)}")

# %% [markdown]
# ### What none of its start states already shows (`other_starts`)
#
# A command given in several start states asks for what holds in none of them (`groundlang.other_starts`; README, "What none of its start states already shows"). `evaluate` follows each test command from one start with the others given. Below: the first command about a chair that names no side (among the first 60, in 8x8 layouts) whose share on one lifted task in its first layout falls by at least 0.1 once its other start states are given: its posterior alone, and given them, beside what its pairs show.

# %%
def changed_by_other_starts(phrase, limit=60):
    sided = ("left", "right", "west", "east", "north", "south", "unless", "not")
    candidates = [c for c in commands if has(c, phrase) and not any(w in c.text.lower().split() for w in sided)
                  and all(p.start.layout.width <= 9 for p in c.pairs)]
    for c in candidates[:limit]:
        first, others = c.pairs[0].start, [p.start for p in c.pairs[1:]]
        alone = learner.posterior(c.text, first)
        given = learner.posterior(c.text, first, other_starts=others)
        after = given.lifted_tasks()
        if any(share - after.get(task, 0.0) >= 0.1 for task, share in alone.lifted_tasks().items()):
            return c, alone, given
    return None


found = changed_by_other_starts("chair")
if found is None:
    print("no such command here: in these layouts no start already shows a reading of the others")
else:
    c, alone, given = found
    print(f"{c.text!r} ({c.path.name}, line {c.line}); its pairs show: {shown_task(c)}")
    print("\nin its first layout, from the words alone:")
    print(alone.table(4))
    print("\ngiven its other two start states:")
    print(given.table(4))
