# %% [markdown]
# # 03 · Ablations: language model × task library × training size
#
# Which parts of groundlang earn their keep? `groundlang ablate` evaluates every cell of the grid
#
# * **language model**: `bow` (bag of words, the paper's Model 0 language model), `ibm2` (IBM Model 2 over machine strings), `parse` (words generated through the parse's logical form);
# * **task library**: `authored` (the shipped `tasks.lp`) or `discovered` (lifted tasks found from the demonstrations alone, no words, no labels);
# * **training size**: seeded subsets stratified by demonstration, nested so that a learning curve adds data rather than resampling;
#
# and writes the rows as JSON. This notebook reads that JSON and shows the table and the plots. With `GROUNDLANG_ABLATION_JSON=path` it shows an existing run (for example the crowd-sourced corpus, see the end); otherwise it runs the grid on the small example corpus shipped with groundlang. In quick mode (`GROUNDLANG_QUICK=1`, as in CI) the grid is smaller.

# %%
import json
import os
import subprocess
import sys
from pathlib import Path

QUICK = os.environ.get("GROUNDLANG_QUICK") == "1"  # CI: smaller grid, same story
# %matplotlib inline
import matplotlib.pyplot as plt

from groundlang.ablation import AblationResult, plot_ablation
from groundlang.corpus import example_corpus_path

examples = example_corpus_path()
json_path = Path(os.environ.get("GROUNDLANG_ABLATION_JSON", "ablation.json"))
command = [
    sys.executable, "-m", "groundlang.cli", "--quiet", "ablate",
    "--corpus", str(examples), "--palette", "sokoban", "--labels", str(examples / "labels.csv"),
    "--language-models", "bow,parse" if QUICK else "bow,ibm2,parse",
    "--libraries", "authored,discovered",
    "--sizes", "12,24" if QUICK else "8,12,16,24",
    "--protocol", "loo", "--json", str(json_path),
] + (["--limit", "12"] if QUICK else [])  # quick: score 12 commands per cell
if "GROUNDLANG_ABLATION_JSON" in os.environ and json_path.exists():
    print(f"reading {json_path}")
else:
    print("$ groundlang " + " ".join(command[4:]).replace(str(examples), "<examples>"))
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode not in (0, 1):  # 1: some fold failed; the rows still say which
        raise RuntimeError(done.stderr)
    print(done.stdout)
result = AblationResult.from_json(json.loads(json_path.read_text()))
print(f"{Path(result.corpus).name}: {result.corpus_size} instances, protocol {result.protocol}, seed {result.seed}")

# %% [markdown]
# ## The table
#
# Accuracy is the share of commands whose executed plan reaches the gold goal, with a 95% Wilson interval. Below the full corpus size, `loo` scores the held-out remainder (protocol `heldout`): one model trained on the subset, every scored command unseen. `seconds` include building the cell's library (discovery runs once per size and is shared by the language models). `tasks` are the lifted tasks of the library used: discovery should find `agentToRoom` and `toyToRoom` from the demonstrations alone.

# %%
print(result.table())
failed = [r for r in result.rows if r.error]
print(f"{len(failed)} failed cells" + "".join(f"\n  {r.language_model}/{r.library}/{r.size}: {r.error}" for r in failed))

# %% [markdown]
# ## Learning curves
#
# One line per (language model, library): solid for the authored library, dashed for the discovered one. Error bars are the Wilson intervals; on a corpus of 24 commands they are wide, so read the plot for trends, not for the third digit.

# %%
fig, ax = plt.subplots(figsize=(7, 4.2))
plot_ablation(result.rows, ax=ax, title=f"{Path(result.corpus).name}: accuracy by training size")
fig.tight_layout()
plt.show()

# %% [markdown]
# ## At the largest training size
#
# The same rows at the largest size, side by side: blue bars use the authored library, orange ones the discovered library.

# %%
largest = max(r.size for r in result.rows)
fig, ax = plt.subplots(figsize=(7, 3.8))
plot_ablation([r for r in result.rows if r.size == largest], ax=ax, title=f"training size {largest}")
fig.tight_layout()
plt.show()
best = max((r for r in result.rows if r.error is None and r.size == largest), key=lambda r: r.accuracy)
print(f"best at size {largest}: {best.language_model} with the {best.library} library, "
      f"{best.accuracy:.1%} [{best.ci_low:.1%}, {best.ci_high:.1%}] in {best.seconds:.1f} s")

# %% [markdown]
# ## On the crowd-sourced corpus
#
# The same command runs the grid on the commands-to-tasks corpus (not part of the repository; see its README), then this notebook shows it with `GROUNDLANG_ABLATION_JSON=ablation-real.json`:
#
# ```
# groundlang ablate --corpus ../shared/data/commands-to-tasks/allTurkTrainLimitedCommand --palette sokoban \
#     --labels ../shared/data/commands-to-tasks/labels.csv --language-models bow,ibm2,parse \
#     --libraries authored,discovered --sizes 24,60,120,240 --protocol loo --workers 2 \
#     --json ablation-real.json --plot ablation-real.png
# ```
#
# Add `--ray auto` (with the `ray` extra installed) to send the cells to a Ray cluster instead.
