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

.PHONY: book test venv lock clean benchmarks notebooks browser-test

venv: $(STAMP)

$(STAMP): requirements.lock pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	$(BIN)/python -m pip install --quiet -r requirements.lock
	$(BIN)/python -m pip install --quiet --no-deps -e .
	$(BIN)/python -m ipykernel install --prefix $(VENV) --name python3 >/dev/null
	touch $(STAMP)

## Build the whole book, every notebook executed; fails on any cell error or Sphinx warning.
## The build log drops two lines the kernels print that are not problems of the book: ipykernel's
## notice that a kernel talks to the build over local TCP without encryption, and the
## "KeyboardInterrupt caught in kernel" that jupyter_client's interrupt-before-shutdown causes
## when a kernel is still finishing a message. It ends with the execution time of every chapter.
book: $(STAMP)
	rm -rf _build/html _build/.doctrees
	mkdir -p _build
	set -o pipefail; $(BIN)/jupyter-book build . --warningiserror --nitpick --keep-going --builder html 2>&1 \
	  | sed -u -e '/Kernel is running over TCP without encryption/d' \
	           -e '/KeyboardInterrupt caught in kernel/d' | tee _build.log
	@awk -v root="$(CURDIR)/" '/: Executed notebook in [0-9.]+ seconds/ { \
	    f = $$1; sub(/:$$/, "", f); sub(root, "", f); \
	    for (i = 1; i < NF; i++) if ($$i == "in") t = $$(i + 1); \
	    printf "  %-45s %8.1f s\n", f, t; total += t } \
	  END { print "  ---------------------------------------------------------"; \
	        printf "  %-45s %8.1f s\n", "total execution time", total }' _build.log \
	  | { echo "Execution time per chapter:"; cat; }
	@echo "Book built: $(abspath _build/html/index.html)"

## Plain .ipynb copies of the chapters (outputs not executed) under _build/notebooks/, which the book
## ignores (a .ipynb beside a chapter is excluded too, see exclude_patterns in _config.yml).
notebooks: $(STAMP)
	for f in $$(grep -rl --include='*.md' '^jupytext:' book); do \
	  mkdir -p "_build/notebooks/$$(dirname $$f)" && $(BIN)/jupytext --quiet --to ipynb --output "_build/notebooks/$${f%.md}.ipynb" "$$f" || exit 1; \
	done
	@echo "Notebooks in $(abspath _build/notebooks)"

## Every page of the built book in headless Chromium (Debian's package, installed if absent),
## at 1280 and 390 px, no network; screenshots in _build/screenshots/ (tests/browser/check_book.py).
CHROMIUM := /usr/bin/chromium
browser-test: $(STAMP)
	@test -f _build/html/index.html || { echo "No built book: run make book first"; exit 2; }
	test -x $(CHROMIUM) || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; }
	$(BIN)/python tests/browser/check_book.py --html _build/html --screenshots _build/screenshots
	$(BIN)/python tests/browser/check_explorables.py --html _build/html

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
