# %% [markdown]
# # 04 · The paper's walkthrough
#
# MacGlashan, Babeş-Vroman et al., "Learning to Interpret Natural Language Instructions" (2012), explain their models on small examples. This notebook recomputes them with groundlang:
#
# 1. **Model 0** (Algorithm 1, hand-coded EM over unigram words given reward functions) on two tasks — *take the star to the green room* and *go to the green room* — with three training sentences each, tested on "Go to green room." and "Go with the star to green.";
# 2. the same data through the Pyro model with the **bag-of-words** and the **parse-aligned** language models;
# 3. the three **Model 1 scenarios** on "Push the star into the green room": a new colour word, a new command with a known task library, and learning from scratch.
#
# The paper's figures come from its own implementation and layouts, which are not available: the numbers below are groundlang's, on layouts that follow the paper's descriptions. Where the paper reports a number we cannot recompute, we say so.

# %%
import os
QUICK = os.environ.get("GROUNDLANG_QUICK") == "1"  # CI: smaller work, same story
# %matplotlib inline
import matplotlib.pyplot as plt
import numpy as np
from pathlib import Path
import re
import torch
from groundlang.corpus import Instance, example_corpus_path, read_corpus, parse_state
from groundlang.examples.build import shortest_demonstration
from groundlang.inference.likelihoods import behaviour_likelihood_table
from groundlang.inference.model0 import model0_em, sentence_log_likelihood
from groundlang.learner import Learner
from groundlang.logic.atoms import parse_goal, format_goal
from groundlang.model.world import replay
from groundlang.render import draw_state

def demonstration(state, goal, command):
    actions = shortest_demonstration(state, goal)
    return Instance(Path(f"{command}.txt"), command, tuple(actions), replay(state, actions))


# %% [markdown]
# ## Model 0: two tasks, three sentences each
#
# The example corpus's layout (green room west); each task demonstrated once, described three ways.

# %%
examples = {i.name: i for i in read_corpus(example_corpus_path(), "sokoban")}
start_star = examples["star2green_0"].initial_state
start_agent = examples["agent2green_0"].initial_state
TASKS = {"star to green": parse_goal("toyInRoom(block0, room0)"),
         "agent to green": parse_goal("agentInRoom(agent0, room0)")}
SENTENCES = {
    # The same sentences as tests/test_model0.py, which checks Model 0's numbers.
    "star to green": ["Take the star to the green room.", "Move the star into the green room.",
                      "Push the star to the green room."],
    "agent to green": ["Go to the green room.", "Go into the green room.", "Go to green."],
}
train = [demonstration(start_star if task == "star to green" else start_agent, TASKS[task], s)
         for task, sentences in SENTENCES.items() for s in sentences]
goals = list(TASKS.values())
behaviour = torch.as_tensor(np.asarray(behaviour_likelihood_table(train, [goals] * len(train), cache_dir=False)))
print("log Pr(demonstration | task), rows = training sentences:")
print(behaviour.numpy().round(1))

def words(sentence):
    return re.findall(r"[a-z]+", sentence.lower())

vocab = sorted({w for inst in train for w in words(inst.command)})
def counts(sentence):
    c = torch.zeros(len(vocab))
    for w in words(sentence):
        if w in vocab:  # unseen words ("with") carry no evidence in Model 0
            c[vocab.index(w)] += 1
    return c

result = model0_em(torch.stack([counts(i.command) for i in train]), behaviour)
print("EM iterations:", result.iterations)
fig, ax = plt.subplots(figsize=(10, 2.8))
ax.imshow(result.word_probs.numpy(), cmap="viridis", aspect="auto")
ax.set_xticks(range(len(vocab)), vocab, rotation=45, ha="right"); ax.set_yticks([0, 1], list(TASKS))
ax.set_title("Model 0: Pr(word | task)"); fig.tight_layout()

# %%
TESTS = ["Go to green room.", "Go with the star to green."]
model0_posteriors = {}
for sentence in TESTS:
    ll = sentence_log_likelihood(result, counts(sentence))
    model0_posteriors[sentence] = torch.softmax(ll, 0).numpy()
    print(f"{sentence!r:32s}", {t: round(float(p), 3) for t, p in zip(TASKS, model0_posteriors[sentence])})

# %% [markdown]
# ## The Pyro model: bag of words vs parse-aligned
#
# The same six instances through `Learner`, with a library of the two lifted tasks of the example (`toyToRoom`, `agentToRoom`), so that the comparison with Model 0's two reward functions is like for like; we report the posterior over lifted tasks. The paper's argument is that a model which parses the command sees "the star" as an argument and sends "Go with the star to green." to the toy task. The cell below prints what groundlang measures, whichever way it goes.

# %%
from groundlang.logic.tasks import TaskLibrary, format_lifted_task

default = TaskLibrary.load()
two_tasks = TaskLibrary.from_text("".join(format_lifted_task(default.task(n)) for n in ("toyToRoom", "agentToRoom")))
LIFTED = {"star to green": "toyToRoom", "agent to green": "agentToRoom"}
rows = {}
for lm in ["bow", "parse"]:
    learner = Learner(language_model=lm, library=two_tasks, cache_dir=False).fit(train)
    for sentence in TESTS:
        lifted = learner.posterior(sentence, start_star).lifted_tasks()
        rows[(lm, sentence)] = [lifted.get(LIFTED[t], 0.0) for t in TASKS]
        print(f"{lm:5s} {sentence!r:32s}", {t: round(p, 3) for t, p in zip(TASKS, rows[(lm, sentence)])})
for name, probs in [("Model 0", model0_posteriors[TESTS[1]]), ("Pyro bow", rows[("bow", TESTS[1])]),
                    ("Pyro parse", rows[("parse", TESTS[1])])]:
    verdict = "toy task" if probs[0] > probs[1] else "agent task"
    print(f"{name:10s} sends {TESTS[1]!r} to the {verdict} ({max(probs):.2f})")
fig, axes = plt.subplots(1, 2, figsize=(11, 3.2), sharey=True)
for ax, sentence in zip(axes, TESTS):
    labels = ["Model 0 (EM)", "Pyro bow", "Pyro parse"]
    values = [model0_posteriors[sentence], rows[("bow", sentence)], rows[("parse", sentence)]]
    x = np.arange(len(labels))
    for k, task in enumerate(TASKS):
        ax.bar(x + (k - 0.5) * 0.38, [v[k] for v in values], 0.38, label=task)
    ax.set_xticks(x, labels); ax.set_ylim(0, 1); ax.set_title(repr(sentence))
axes[0].set_ylabel("posterior"); axes[0].legend()
fig.tight_layout()

# %% [markdown]
# **Measured (seed 0), printed above:** Model 0 sends "Go to green room." to the agent task and, as in the paper, *wrongly* sends "Go with the star to green." there too: in six sentences "go" occurs only with the agent task and outweighs "star" (tests/test_model0.py checks these numbers: 3.2e-7 vs 9.5e-5 for the first sentence, 1.6e-10 vs 8.6e-10 for the second). The Pyro bag of words makes the same mistake. The parse-aligned model sends it to the toy task (about 0.9, printed above; tests/test_model0.py checks the verdict): the command names the star, and the mention model has learned that commands name the toys their task moves, not bystanders, which is the paper's point that the structure of the command fixes this example.

# %% [markdown]
# ## Model 1 scenarios: "Push the star into the green room"
#
# One small world as the paper describes it: a green room along the north, red and blue rooms below, the yellow star in the red–blue doorway and a magenta moon in the green room. The demonstration is the shortest path taking the star into the green room — it passes *through* the red room.

# %%
from groundlang.inference.mlirl import mlirl
from groundlang.model.features import feature_matrix, position_atoms
from groundlang.model.pf_tables import pf_tables
from groundlang.model.statespace import enumerate_states, trajectory_indices

COMMAND = "Push the star into the green room"
WORLD = ("room,5,0,7,8,4 room,10,0,4,4,0 room,1,4,4,8,0 door,2,4,2,4 door,6,4,6,4 door,4,2,4,2 "
         "block,12,0,4,2 block,7,1,7,6 agent,5,6")
GOLD = parse_goal("toyInRoom(block0, room0)")
demo = demonstration(parse_state(WORLD, "sokoban"), GOLD, COMMAND)
IRL = dict(temperature=0.5, l1=0.1, nonnegative=True)

def mlirl_weights(atoms):
    space = enumerate_states(demo.initial_state)
    features = feature_matrix(space, atoms, pf_tables(space.layout))
    states = trajectory_indices(space, list(demo.states))
    return mlirl(space.next_state, features, [(states, [int(a) for a in demo.actions])], **IRL).weights

ax = draw_state(demo.initial_state, trajectory=demo.states, title=f"{COMMAND!r}: {len(demo.actions)} moves")
ax.figure

# %% [markdown]
# ### Scenario 1: learning a new colour name
#
# Every word known but "green": the verb names `toyToRoom`, "star" binds the toy, so three groundings remain; IRL over their features picks the green room, and "green" is tied to `roomIsGreen`.

# %%
from groundlang.grammar.lexicon import SemanticLexicon
from groundlang.grammar.parser import parse
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.domain_words import domain_lexicon
from groundlang.model.tasks import candidate_tasks, narrow_by_known

library = TaskLibrary.load()
lexicon = SemanticLexicon({"push": {"toyToRoom": 1.0}, "star": {"toyIsStar": 1.0}})
print(parse(COMMAND, lexicon=lexicon, word_lexicon=domain_lexicon())[0].logical_form.paper_str())
narrowed = narrow_by_known(candidate_tasks(demo.initial_state, library), {"T": {"toyIsStar"}}, task="toyToRoom")
weights = mlirl_weights([n.grounded.goal[0] for n in narrowed])
table = behaviour_likelihood_table([demo], [[n.grounded.goal for n in narrowed]], cache_dir=False)[0]
posterior = np.exp(table - table.max()); posterior /= posterior.sum()
for n, w, ll, p in zip(narrowed, weights, table, posterior):
    print(f"{n.grounded.goal_text:28s} MLIRL weight {w:6.2f}  log-lik {ll:8.2f}  posterior {p:.3g}")
fig, ax = plt.subplots(figsize=(6, 2.4))
ax.barh([n.grounded.goal_text for n in narrowed], weights); ax.invert_yaxis()
ax.set_xlabel("MLIRL weight"); ax.set_title("scenario 1: induced features toyIn(star, r)")
fig.tight_layout()

# %% [markdown]
# ### Scenario 2: a new command with a known task library
#
# No word known. Behaviour alone, over all 19 groundings, picks `toyToRoom(star, green room)`. MLIRL over every position PF gives the features the paper lists (it reports 1.91 `toyIn(t1, r1)`, 1.12 `agentTouchingToy(t1)`, 0.80 `agentIn(r1)`; its weights' scale and its layout differ from ours, so only the ranking compares: here the agent ends in the doorway behind the star, so the third feature is `agentInDoor`).

# %%
import math
candidates = candidate_tasks(demo.initial_state, library)
sizes = {t: sum(g.task == t for g, _ in candidates) for t in library.names}
table = behaviour_likelihood_table([demo], [[g.goal for g, _ in candidates]], cache_dir=False)[0]
log_post = np.array([-math.log(len(sizes)) - math.log(sizes[g.task]) for g, _ in candidates]) + table
post = np.exp(log_post - log_post.max()); post /= post.sum()
best = candidates[int(np.argmax(post))][0]
print(len(candidates), "groundings; best:", best, f"posterior {post.max():.6f}")
atoms = position_atoms(demo.initial_state.layout)
w = mlirl_weights(atoms)
top = sorted(zip(atoms, w.tolist()), key=lambda aw: -aw[1])[:5]
fig, ax = plt.subplots(figsize=(6, 2.6))
ax.barh([str(a) for a, _ in top], [x for _, x in top]); ax.invert_yaxis()
ax.set_xlabel("MLIRL weight"); ax.set_title("scenario 2: top features over all position PFs")
fig.tight_layout()

# %% [markdown]
# ### Scenario 3: learning from scratch
#
# No words, no tasks: task discovery lifts the top-weighted features of the demonstration into a lifted task, written out as ASP a person can read and edit.

# %%
import tempfile
from groundlang.inference.discovery import discover_tasks, write_library

found = discover_tasks([demo], cache_dir=False)
report = found.demonstrations[0]
print("top features:", [(str(a), round(x, 2)) for a, x in report.top_features])
print("discovered:", [str(t) for t in found.tasks])
with tempfile.TemporaryDirectory() as tmp:
    print(Path(write_library(found, Path(tmp) / "scratch.lp")).read_text())

# %% [markdown]
# ### What cannot be recomputed
#
# * The paper's Model 0 and Model 1 tables were computed on its own layouts and demonstrations, which were not published with it; the numbers here are groundlang's on layouts following the paper's text.
# * The MLIRL weights' scale depends on the regulariser and temperature (here L1 0.1, temperature 0.5), so only their ranking is comparable to the paper's 1.91 / 1.12 / 0.80.
