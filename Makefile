# fdi-book: the two entry points are `make book` and `make test`.
SHELL := /bin/bash
# Each creates/updates the virtual environment .venv from requirements.lock by itself.
PYTHON ?= $(shell command -v python3.11 2>/dev/null || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# All matrices here are small: one BLAS thread per process avoids oversubscription (see
# fdi_lib/threads.py); Monte Carlo parallelism is over processes.
export OPENBLAS_NUM_THREADS := 1
export OMP_NUM_THREADS := 1
export MKL_NUM_THREADS := 1

.PHONY: book test venv lock clean benchmarks

venv: $(STAMP)

$(STAMP): requirements.lock pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	$(BIN)/python -m pip install --quiet -r requirements.lock
	$(BIN)/python -m pip install --quiet --no-deps -e .
	$(BIN)/python -m ipykernel install --prefix $(VENV) --name python3 >/dev/null
	touch $(STAMP)

## Build the whole book, every notebook executed; fails on any cell error or Sphinx warning.
## Reproductions run by the chapters are cached for this build only, for the claims ledger.
book: export FDI_RESULTS_CACHE := $(CURDIR)/_build/results-cache
book: $(STAMP)
	rm -rf _build/html _build/.doctrees _build/results-cache
	set -o pipefail; $(BIN)/jupyter-book build . --warningiserror --nitpick --keep-going --builder html 2>&1 | tee _build.log
	@echo "Book built: $(abspath _build/html/index.html)"

## Run the whole test suite.
test: $(STAMP)
	$(BIN)/python -m pytest -q

benchmarks: $(STAMP)
	for f in benchmarks/bench_*.py; do echo "== $$f"; $(BIN)/python $$f || exit 1; done

## Re-pin requirements.lock from the current environment (maintainers only).
lock:
	$(BIN)/python -m pip freeze --exclude-editable | grep -v '^fdi[-_]lib' > requirements.lock

clean:
	rm -rf _build _build.log
