# The two commands of the README's quick start, plus what they need.
# Both create .venv on first use; torch is pinned to the CPU wheel first so
# that nothing pulls a CUDA build.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: test-slow demo test bench notebooks clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet "torch==2.13.0"
	$(BIN)/python -m pip install --quiet -e ".[test,progress,plot,gym,notebooks,ray]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/groundlang demo --out demo.png

# Two test processes (pytest-xdist): the suite is CPU-bound and single-threaded in most tests, so the
# second core halves its wall time. Tests are spread one by one (--dist loadgroup), but a module marked
# xdist_group runs in one process, so that its costly module fixture (the harder corpus evaluated under the
# train protocol) is built once, not once per process. `$(BIN)/python -m pytest -n 0` runs it in one process.
# `make test` leaves out the tests marked slow (whole corpora evaluated, notebooks run, fuzzing): under ten
# minutes on 2 cores. `make test-slow` runs only those; CI runs both.
test: $(STAMP)
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m "not slow"

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m slow

# The notebooks' .py files are their source: write each paired .ipynb from it (outputs stay stripped).
notebooks: $(STAMP)
	$(BIN)/jupytext --sync notebooks/[0-9][0-9]_*.py

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) build *.egg-info
