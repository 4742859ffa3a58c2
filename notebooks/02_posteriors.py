# %% [markdown]
# # 02 · Posteriors: what the learner believes a command means
#
# Train on the example corpus (and on the crowd-sourced commands-to-tasks corpus when it is present and `GROUNDLANG_QUICK` is not set), then look inside: the posterior over lifted tasks, groundings and binding constraints; the logical forms of a command and how probable each reading is once aligned with the world; the lexicon as a heat map; and how the posterior sharpens as training data grows.

# %%
import os
QUICK = os.environ.get("GROUNDLANG_QUICK") == "1"  # CI: smaller work, same story
# %matplotlib inline
import matplotlib.pyplot as plt
import numpy as np
from pathlib import Path
import groundlang
from groundlang.animation import posterior_bar_chart
from groundlang.corpus import example_corpus_path, read_corpus, read_state_file
from groundlang.learner import Learner
from groundlang.logic.atoms import format_goal
from groundlang.render import draw_state

examples = example_corpus_path()
# The crowd corpus beside the repository (../shared/data), wherever the notebook is run from.
CROWD = Path(os.environ.get("GROUNDLANG_CORPUS", Path(groundlang.__file__).resolve().parent.parent.parent
                            / "shared" / "data" / "commands-to-tasks"))
corpus = read_corpus(examples, "sokoban")
novel = {n: read_state_file(examples / f"novel_{n}.state", "sokoban") for n in "abc"}
learner = Learner(language_model="parse", cache_dir=False).fit(corpus.instances)
print("trained on", len(corpus), "instances")

# %% [markdown]
# ## Posterior over (task, grounding, constraint) in a novel layout

# %%
state = novel["a"]
command = "take the star to the red room"
post = learner.posterior(command, state)
print(post.table(6))
print()
print("lifted tasks:", {k: round(v, 4) for k, v in post.lifted_tasks().items()})
fig, axes = plt.subplots(1, 3, figsize=(15, 3.8), gridspec_kw={"width_ratios": [1, 1.2, 1.2]})
draw_state(state, ax=axes[0], title="novel_a")
posterior_bar_chart(post, kind="goals", top=5, ax=axes[1])
posterior_bar_chart(post, kind="lifted", ax=axes[2])
fig.tight_layout()

# %% [markdown]
# ## Logical forms and alignments
#
# The grammar gives each command one or more readings with prior probabilities; the parse-aligned model re-weighs them by how well their noun phrases align with the objects of the likely goals.

# %%
for command in ["take the star to the red room", "go to the green room",
                "push the star from the blue room into the green room"]:
    post = learner.posterior(command, novel["b"])
    (first, p1), (second, p2) = post.goals()[:2]
    print(repr(command), "->", format_goal(first), f"{p1:.3f}; next", format_goal(second), f"{p2:.3f}")
    for reading, p in zip(post.readings, post.reading_probabilities):
        print(f"   prior {reading.probability:.2f}  posterior {p:.2f}  {reading.logical_form.paper_str()}")
ax = posterior_bar_chart(post, kind="readings")
ax.figure

# %% [markdown]
# The third command ties: no training command of the example corpus says "from", and none shows the agent and the
# star ending in two rooms, so the two ways of placing them are equally likely (the crowd corpus's model reads it as
# the star's task, 1.00, and pushes the star into the room this palette names blue: that corpus's workers saw the
# palette's blue room drawn teal and often called it green: its model reads "green" as `roomIsBlue`, 0.97). `follow`
# asks there rather than acting: its end would satisfy 0.49 of the posterior (the most probable goal's 0.48 and a
# little more), below its `--min-confidence` of 0.7 ("Knowing when it does not know" in the README).
#
# Which object each noun phrase of the most probable reading names, under the most probable interpretation
# (`Learner.alignments`: exact with the mention model).

# %%
for row in learner.alignments("push the star from the blue room into the green room", novel["b"]):
    named = ", ".join(f"{obj or 'nothing'} as {role} {p:.2f}" for obj, role, p in row.objects[:2])
    print(f"{row.key:<14} {' '.join(row.words):<12} {named}")

# %% [markdown]
# ## The lexicon as a heat map
#
# `P(token | word)` for the words and the semantic tokens they most probably mean.

# %%
lexicon = learner.lexicon(top=3)
words = [w for w in lexicon if lexicon[w][0][1] > 0.3]
tokens = list(dict.fromkeys(t for w in words for t, _ in lexicon[w][:1]))
full = learner.lexicon(top=len(learner.vocab.tokens))
matrix = np.array([[dict(full[w]).get(t, 0.0) for t in tokens] for w in words])
fig, ax = plt.subplots(figsize=(0.55 * len(tokens) + 2, 0.3 * len(words) + 1.5))
im = ax.imshow(matrix, cmap="viridis", vmin=0, vmax=1, aspect="auto")
ax.set_xticks(range(len(tokens)), tokens, rotation=60, ha="right", fontsize=8)
ax.set_yticks(range(len(words)), words, fontsize=8)
fig.colorbar(im, ax=ax, label="P(token | word)")
ax.set_title("learned lexicon (example corpus)")
fig.tight_layout()

# %% [markdown]
# ## Does the posterior sharpen as training data grows?
#
# Train on the first *n* commands of every task (same demonstrations) and ask, in the three novel layouts, for the probability of the right goal for each task's first command. On this tiny corpus the curve is measured, not assumed: it need not be monotone (a second and third phrasing per task first spreads the verbs' meaning before all four pin it down; the full run's three phrasings show it, the quick run, `GROUNDLANG_QUICK=1`, skips three and rises throughout).

# %%
from groundlang.evaluation import translate_goal
from groundlang.labels import read_labels, label_for

labels = read_labels(examples / "labels.csv")
by_prefix = {}
for inst in corpus:
    by_prefix.setdefault(inst.prefix, []).append(inst)
sizes = [1, 2, 4] if QUICK else [1, 2, 3, 4]
mean_p, min_p = [], []
for n in sizes:
    train = [i for group in by_prefix.values() for i in group[:n]]
    model = Learner(cache_dir=False).fit(train)
    ps = []
    for group in by_prefix.values():
        inst = group[0]
        gold = label_for(inst, labels)
        for s in novel.values():
            target = translate_goal(gold, inst.initial_state, s)
            ps.append(dict(model.posterior(inst.command, s).goals()).get(target, 0.0))
    mean_p.append(float(np.mean(ps))); min_p.append(float(np.min(ps)))
    print(f"{len(train):3d} training instances: P(right goal) mean {mean_p[-1]:.3f}, min {min_p[-1]:.3f}")
fig, ax = plt.subplots(figsize=(5, 3.2))
ax.plot([6 * n for n in sizes], mean_p, "o-", label="mean")
ax.plot([6 * n for n in sizes], min_p, "s--", label="worst command")
ax.set_xlabel("training instances"); ax.set_ylabel("posterior of the right goal")
ax.set_ylim(0, 1); ax.legend(); ax.set_title("6 commands x 3 novel layouts")
fig.tight_layout()

# %% [markdown]
# ## The crowd-sourced corpus (when present, full mode only)
#
# The commands-to-tasks corpus is not part of the repository; this cell uses it where it is, with the real, messy commands.

# %%
shared = CROWD / "allTurkTrain"
if QUICK or not shared.is_dir():
    print("skipped:", "quick mode" if QUICK else f"{shared} not found")
else:
    crowd = read_corpus(shared, "sokoban", skip_inconsistent=True)
    crowd_learner = Learner(language_model="parse").fit(crowd.instances, progress=False)
    inst = crowd.instances[0]
    print(inst.command)
    post = crowd_learner.posterior(inst.command, inst.initial_state)
    print(post.table(5))
    posterior_bar_chart(post, kind="goals", top=5).figure

# %% [markdown]
# ## Knowing when it does not know: calibration
#
# Following's confidence is how likely what was meant holds where it ends: the posterior mass of the goals its end satisfies (`success_confidence`; where it plans for one goal alone, that goal's probability, goals with the same outcome in the layout counted as one). Leave-one-out on both crowd folders (full mode, when the corpus is present; the example corpus otherwise) gives each held-out command a confidence and whether acting on it was right. The **reliability diagram** sets accuracy against confidence per bin (on the diagonal: calibrated); the **risk-coverage curve** gives the accuracy of the commands acted on when the learner abstains from the least confident first. `follow` asks instead of acting below `--min-confidence` (0.7, the dotted line's coverage).

# %%
from groundlang.confidence import format_calibration
from groundlang.evaluation import evaluate
from groundlang.labels import read_labels

crowd_root = CROWD
if QUICK or not (crowd_root / "allTurkTrain").is_dir():
    runs = {"example corpus": (corpus, read_labels(examples / "labels.csv"))}
else:
    labels = read_labels(crowd_root / "labels.csv")
    runs = {name: (read_corpus(crowd_root / name, "sokoban"), labels)
            for name in ("allTurkTrainLimitedCommand", "allTurkTrain")}
fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
for name, (data, gold) in runs.items():
    result = evaluate(data, gold, workers=2)
    report = result.calibration
    print(name, f"accuracy {result.accuracy:.2%}")
    print(format_calibration(report))
    bins = report["reliability"]
    axes[0].plot([b["confidence"] for b in bins], [b["accuracy"] for b in bins], "o-", label=name)
    cov, acc = zip(*report["risk_coverage"])
    axes[1].plot(cov, acc, label=name)
    axes[1].axvline(report["threshold"]["coverage"], ls=":", color=axes[1].lines[-1].get_color())
axes[0].plot([0, 1], [0, 1], "k--", lw=0.8)
axes[0].set_xlabel("confidence (bin mean)"); axes[0].set_ylabel("accuracy"); axes[0].set_title("reliability")
axes[1].set_xlabel("coverage (share of commands acted on)"); axes[1].set_ylabel("accuracy on those")
axes[1].set_title("risk-coverage"); axes[1].set_ylim(0.85, 1.005)
for ax in axes:
    ax.legend(fontsize=8)
fig.tight_layout()
