# The two commands of the README's quick start, plus what they need.
# Both create .venv on first use; torch 2.13.0 is installed first, so that nothing else pulls another build.
# Which wheel pip takes is pip's configuration's: a CPU wheel where it offers one (a find-links folder, as on
# the project's machine); on plain PyPI under Linux that is the CUDA build. TORCH_INDEX names an index to take
# torch from instead: make TORCH_INDEX=https://download.pytorch.org/whl/cpu
TORCH_INDEX ?=
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: test-slow demo test bench notebooks clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet "torch==2.13.0" $(if $(TORCH_INDEX),--index-url $(TORCH_INDEX))
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
